//! Deforming bodies: linear blend skinning, glTF skins read back, vertex caches read back, and
//! collision with a deforming body (inverse skinning into the rest pose's SDF) against exact
//! distances.

mod common;

use drapekit::body::cache::read_cache;
use drapekit::body::deform::{Deformation, Timeline};
use drapekit::body::gltf_read::{parse_skinned, read_skinned};
use drapekit::body::gltf_write::skinned_glb;
use drapekit::body::skin::{
    skin, Channel, Clip, Influence, Interpolation, Skeleton, SkinnedMesh, Trs, Values,
};
use drapekit::mesh::TriMesh;
use glam::{Mat4, Quat, Vec3};
use std::path::{Path, PathBuf};

fn temp(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drapekit-deforming-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Two joints: a root at the origin and a tip 1 m along x, bound where they stand.
fn two_joints() -> Skeleton {
    let rest = vec![
        Trs::IDENTITY,
        Trs {
            translation: Vec3::X,
            ..Trs::IDENTITY
        },
    ];
    let mut s = Skeleton {
        names: vec!["root".into(), "tip".into()],
        parents: vec![None, Some(0)],
        rest: rest.clone(),
        inverse_bind: vec![Mat4::IDENTITY; 2],
        base: vec![Mat4::IDENTITY; 2],
    };
    s.bind_to(&rest);
    s
}

fn only(joint: u16) -> Influence {
    Influence {
        joints: [joint, 0, 0, 0],
        weights: [1.0, 0.0, 0.0, 0.0],
    }
}

fn halves() -> Influence {
    Influence {
        joints: [0, 1, 0, 0],
        weights: [0.5, 0.5, 0.0, 0.0],
    }
}

/// The tip turned 90° about z.
fn tip_turned(s: &Skeleton) -> Vec<Trs> {
    let mut locals = s.rest.clone();
    locals[1].rotation = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    locals
}

/// Vertices on the root, on the tip and shared half and half, with the tip turned 90° about z:
/// (0.5, 0, 0) stays; (1.5, 0, 0), 0.5 m out from the tip, turns to (1, 0.5, 0); (1, 0.2, 0)
/// goes half way between staying and turning to (0.8, 0, 0), to (0.9, 0.1, 0).
const REST: [Vec3; 3] = [
    Vec3::new(0.5, 0.0, 0.0),
    Vec3::new(1.5, 0.0, 0.0),
    Vec3::new(1.0, 0.2, 0.0),
];
const TURNED: [Vec3; 3] = [
    Vec3::new(0.5, 0.0, 0.0),
    Vec3::new(1.0, 0.5, 0.0),
    Vec3::new(0.9, 0.1, 0.0),
];

#[test]
fn a_single_bone_rotation_moves_only_its_vertices_by_the_rotation() {
    let s = two_joints();
    let influences = [only(0), only(1), halves()];
    let posed = skin(&REST, &influences, &s.skinning(&tip_turned(&s)));
    // The root's vertex is untouched bit for bit: its matrix is the identity.
    assert_eq!(posed[0], REST[0]);
    for (p, want) in posed.iter().zip(TURNED) {
        // f32 rotation of unit-sized offsets: a few ulps (1e-7 m); 1e-6 m leaves room.
        assert!(p.distance(want) < 1e-6, "{p} != {want}");
    }
}

#[test]
fn the_rigged_mannequins_weights_sum_to_one() {
    let path = common::fixture("bodies/mannequin_rigged.glb");
    let m = read_skinned(&path, "body.path").unwrap();
    assert_eq!(m.influences.len(), m.mesh.positions.len());
    assert!(m.skeleton.len() >= 15, "{} joints", m.skeleton.len());
    for (v, inf) in m.influences.iter().enumerate() {
        let sum: f32 = inf.weights.iter().sum();
        // Four f32 weights normalised to one: within a few ulps of 1.
        assert!((sum - 1.0).abs() < 1e-5, "vertex {v}: weights sum to {sum}");
        assert!(inf.weights.iter().all(|&w| w >= 0.0), "vertex {v}: {inf:?}");
    }
    let names: Vec<&str> = m.clips.iter().map(|c| c.name.as_str()).collect();
    for name in drapekit::body::motions::NAMES {
        assert!(names.contains(&name), "{name} missing from {names:?}");
    }
}

#[test]
fn a_written_skinned_gltf_reads_back_and_poses_as_expected() {
    let s = two_joints();
    let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let body = SkinnedMesh {
        mesh: TriMesh {
            positions: REST.to_vec(),
            triangles: vec![[0, 1, 2]],
        },
        influences: vec![only(0), only(1), halves()],
        skeleton: s,
        clips: vec![Clip {
            name: "bend".into(),
            channels: vec![Channel {
                joint: 1,
                times: vec![0.0, 1.0],
                values: Values::Rotation(vec![Quat::IDENTITY, quarter]),
                interpolation: Interpolation::Linear,
            }],
        }],
    };
    let bytes = skinned_glb(&body, "arm").expect("small");
    let back = parse_skinned(&bytes, None, Path::new("arm.glb"), "body.path").unwrap();
    assert_eq!(back.mesh.triangles, body.mesh.triangles);
    let clip = back.clip("bend").expect("the clip keeps its name");
    let posed = back.posed(&clip.pose(&back.skeleton, 1.0));
    for (p, want) in posed.iter().zip(TURNED) {
        // The file holds the same f32 values; posing rounds as above.
        assert!(p.distance(want) < 1e-6, "{p} != {want}");
    }
    let start = back.posed(&clip.pose(&back.skeleton, 0.0));
    for (p, want) in start.iter().zip(REST) {
        assert!(p.distance(want) < 1e-6, "{p} != {want}");
    }
}

#[test]
fn rotation_keys_must_be_rotations_and_cubic_tangents_may_be_zero() {
    let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let zero = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    let with_keys = |values: Vec<Quat>, interpolation| SkinnedMesh {
        mesh: TriMesh {
            positions: REST.to_vec(),
            triangles: vec![[0, 1, 2]],
        },
        influences: vec![only(0), only(1), halves()],
        skeleton: two_joints(),
        clips: vec![Clip {
            name: "bend".into(),
            channels: vec![Channel {
                joint: 1,
                times: vec![0.0, 1.0],
                values: Values::Rotation(values),
                interpolation,
            }],
        }],
    };
    let read = |body: &SkinnedMesh| {
        let bytes = skinned_glb(body, "arm").expect("small");
        parse_skinned(&bytes, None, Path::new("arm.glb"), "body.path")
    };
    // A cubic spline's in- and out-tangents of zero (as exporters write them): read.
    let cubic = vec![zero, Quat::IDENTITY, zero, zero, quarter, zero];
    let back = read(&with_keys(cubic, Interpolation::CubicSpline)).unwrap();
    let clip = back.clip("bend").expect("the clip keeps its name");
    let posed = back.posed(&clip.pose(&back.skeleton, 1.0));
    for (p, want) in posed.iter().zip(TURNED) {
        assert!(p.distance(want) < 1e-6, "{p} != {want}");
    }
    // A key's value of zero length, or NaN, is no rotation: refused, naming the animation.
    let nan = Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0);
    for bad in [
        with_keys(
            vec![zero, zero, zero, zero, quarter, zero],
            Interpolation::CubicSpline,
        ),
        with_keys(vec![Quat::IDENTITY, nan], Interpolation::Linear),
        with_keys(vec![zero, quarter], Interpolation::Linear),
    ] {
        let e = read(&bad).expect_err("no rotation was read").to_string();
        assert!(e.contains("animation 'bend'"), "{e}");
    }
}

#[test]
fn a_skinned_body_blends_from_its_rest_pose_and_plays_its_clip() {
    // The fixture's one joint turns 45° about y over 1 s; every vertex follows it.
    let path = common::fixture("bodies/skinned_tetra.gltf");
    let m = read_skinned(&path, "body.path").unwrap();
    let rest = m.mesh.positions.clone();
    let timeline = Timeline {
        start: 1.0,
        transition: 0.5,
        plays: 1,
    };
    let d = Deformation::skinned(m, 0, timeline, "test".into());
    assert!((d.end() - 2.5).abs() < 1e-6, "{}", d.end());
    let turned = |deg: f32, t: f32| {
        let q = Quat::from_rotation_y(deg.to_radians());
        for (p, r) in d.positions_at(t).iter().zip(&rest) {
            // f32 slerp and skinning at 0.2 m: ulps; 1e-6 m.
            assert!(p.distance(q * *r) < 1e-6, "t = {t}: {p} != {}", q * *r);
        }
    };
    turned(0.0, 0.5); // before the start
    turned(0.0, 1.25); // the transition into a first frame that is the rest pose
    turned(22.5, 2.0); // half way through the clip
    turned(45.0, 3.0); // its last frame holds
                       // The fastest vertex: 0.2·√2 m from the axis at most, turning π/4 rad/s.
    let fastest = rest.iter().map(|p| p.x.hypot(p.z)).fold(0.0, f32::max);
    let speed = d.max_vertex_speed();
    let want = fastest * std::f32::consts::FRAC_PI_4;
    // Sampled at 60/s as chords of the arc: within 0.1% of the arc speed.
    assert!((speed - want).abs() < 1e-3 * want, "{speed} vs {want}");
}

#[test]
fn a_motion_played_three_times_is_as_fast_as_its_full_timeline_says() {
    // The turn of 45° over 1 s, played three times: each play ends at 45° and the next starts
    // at 0°, a jump of 45° between samples. The speed estimates look at the transition and two
    // plays only; a scan of the whole timeline (every vertex's move between positions sampled
    // 60 times a second, as the estimate samples them) must find nothing faster.
    let m = read_skinned(&common::fixture("bodies/skinned_tetra.gltf"), "body.path").unwrap();
    let timeline = Timeline {
        start: 1.0,
        transition: 0.5,
        plays: 3,
    };
    let d = Deformation::skinned(m, 0, timeline, "test".into());
    let (from, to) = (timeline.start, d.end());
    let samples = ((to - from) * 60.0).ceil() as usize;
    let dt = (to - from) / samples as f32;
    let mut full = 0.0f32;
    for k in 1..=samples {
        let (a, b) = (from + (k - 1) as f32 * dt, from + k as f32 * dt);
        let moved = (d.positions_at(a).iter().zip(d.positions_at(b)))
            .map(|(p, q)| p.distance(q))
            .fold(0.0, f32::max);
        full = full.max(moved / dt);
    }
    let speed = d.max_vertex_speed();
    // The same 60/s grid from the same start over the first two plays, then a repeat: equal
    // but for the rounding of the sample times (f32 at a few seconds, ulps of a speed).
    assert!(
        (speed - full).abs() <= 1e-4 * full,
        "{speed} vs the full scan's {full}"
    );
    // The parts' speed too: the wrap's jump lies within the keys it looks at.
    let one_play = Deformation::skinned(
        read_skinned(&common::fixture("bodies/skinned_tetra.gltf"), "body.path").unwrap(),
        0,
        Timeline {
            plays: 1,
            ..timeline
        },
        "test".into(),
    );
    assert!(d.max_part_speed() > 10.0 * one_play.max_part_speed());
}

/// A closed tetrahedron's OBJ text with the given vertices.
fn tetra_obj(p: &[Vec3]) -> String {
    let mut s: String = p
        .iter()
        .map(|v| format!("v {} {} {}\n", v.x, v.y, v.z))
        .collect();
    s.push_str("f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    s
}

fn tetra(shift: f32) -> Vec<Vec3> {
    [Vec3::ZERO, 0.2 * Vec3::X, 0.2 * Vec3::Y, 0.2 * Vec3::Z]
        .iter()
        .map(|p| *p + shift * Vec3::X)
        .collect()
}

#[test]
fn a_pc2_cache_reads_back() {
    let dir = temp("pc2");
    let frames: Vec<Vec<Vec3>> = (0..3).map(|k| tetra(0.1 * k as f32)).collect();
    let bytes = drapekit::export::pc2::pc2_bytes(&frames, 0.0, 1.0).unwrap();
    let path = dir.join("move.pc2");
    std::fs::write(&path, bytes).unwrap();
    let cache = read_cache(&path, 24.0, 4, "body.cache").unwrap();
    assert_eq!(cache.frames, frames);
    assert_eq!(cache.times, vec![0.0, 1.0 / 24.0, 2.0 / 24.0]);
    // Half way between frames 1 and 2: linear.
    let mid = cache.at(1.5 / 24.0);
    // Interpolation in f32 of positions below 1 m: ulps.
    assert!(mid[0].distance(0.15 * Vec3::X) < 1e-6, "{}", mid[0]);
    let wrong = read_cache(&path, 24.0, 5, "body.cache").unwrap_err();
    assert!(wrong.to_string().contains("body mesh has 5"), "{wrong}");
}

#[test]
fn an_obj_sequence_cache_reads_back() {
    let dir = temp("objseq");
    for k in 1..=3 {
        let text = tetra_obj(&tetra(0.1 * k as f32));
        std::fs::write(dir.join(format!("walk_{k:04}.obj")), text).unwrap();
    }
    let cache = read_cache(&dir.join("walk_####.obj"), 10.0, 4, "body.cache").unwrap();
    assert_eq!(cache.frames.len(), 3);
    assert_eq!(cache.times, vec![0.0, 0.1, 0.2]);
    for (k, f) in cache.frames.iter().enumerate() {
        let want = tetra(0.1 * (k + 1) as f32);
        for (p, w) in f.iter().zip(&want) {
            // Printed with Rust's shortest round-trip form: read back exactly.
            assert_eq!(p, w);
        }
    }
}

/// A closed box of half size `h` as OBJ text (vertices ±h, outward faces).
#[test]
fn a_cached_body_collides_where_its_moved_surface_is() {
    // A 20 cm box that a two-frame cache turns 30° about y and moves 5 cm along x: with one
    // collision part, inverse skinning maps each point back exactly, and near a face's middle
    // the rest SDF is the face's plane distance, which trilinear sampling reproduces.
    let dir = temp("cached-box");
    let (text, corners) = common::box_obj(0.1);
    std::fs::write(dir.join("box.obj"), text).unwrap();
    let turn = Quat::from_rotation_y(30f32.to_radians());
    let shift = Vec3::new(0.05, 0.0, 0.0);
    let moved: Vec<Vec3> = corners.iter().map(|p| turn * *p + shift).collect();
    let bytes = drapekit::export::pc2::pc2_bytes(&[corners.clone(), moved], 0.0, 1.0).unwrap();
    std::fs::write(dir.join("box.pc2"), bytes).unwrap();
    let scene_text = r#"
[cloth.grid]
width_m = 0.2
height_m = 0.2
columns = 4
rows = 4
center_m = [0.0, 1.0, 0.0]
plane = "xz"

[fabric]
preset = "cotton"

[body]
path = "box.obj"
cache = "box.pc2"
cache_fps = 1.0
parts = 1
transition_s = 0.0
thickness_m = 0.003
sdf_resolution_m = 0.01
sdf_cache = false

[solver]
fps = 24
frames = 2
"#;
    let scene_path = dir.join("scene.toml");
    std::fs::write(&scene_path, scene_text).unwrap();
    let scene = drapekit::scene::Scene::load(&scene_path).unwrap();
    let prep = drapekit::sim::prepare(&scene).unwrap();
    let body = prep.params.bodies[0];
    assert_eq!(body.parts, 1);
    let words = &prep.model.colliders[0].sdf.values;
    let parts = drapekit::sim::part_poses(&prep.model, 1.0);
    let mut checked = 0;
    for a in [-0.05f32, 0.0, 0.05] {
        for b in [-0.05f32, 0.0, 0.05] {
            for depth in [-0.02f32, -0.005, 0.0, 0.004, 0.015] {
                // Rest point near the +x face's middle, `depth` out from it.
                let rest = Vec3::new(0.1 + depth, a, b);
                let x = turn * rest + shift;
                let s = drapekit::cpu::deformed_sample(&body, &parts, words, x);
                // The plane distance is linear, so trilinear sampling is exact up to f32
                // rounding of coordinates near 0.1 m (~1e-8 m) and of the fitted pose (the
                // Kabsch fit in f32, ~1e-6 relative at 0.1 m): 2e-5 m leaves room.
                assert!(
                    (s.phi - depth).abs() < 2e-5,
                    "rest {rest}: φ {} != {depth}",
                    s.phi
                );
                let normal = turn * Vec3::X;
                assert!(s.normal.distance(normal) < 1e-3, "{} != {normal}", s.normal);
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 45);
    // Far from the box, no part claims the point.
    let far = drapekit::cpu::deformed_sample(&body, &parts, words, Vec3::new(2.0, 0.0, 0.0));
    assert!(far.phi > 1.0, "{}", far.phi);
}
