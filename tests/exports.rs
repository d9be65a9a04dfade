//! Exports read back: OBJ frames (normals, panel groups), the body beside them, the PC2 point
//! cache and the animated glTF binary, from short CPU runs of shipped scenes.

mod common;

use drapekit::body::motion::Motion;
use drapekit::gpu::AdapterChoice;
use drapekit::run::{run_scene, BackendChoice, RunOptions};
use drapekit::scene::Scene;
use drapekit::sim::prepare;
use glam::{Quat, Vec3};
use std::path::{Path, PathBuf};

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drapekit-exports-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn options(out: &Path, frames: u32) -> RunOptions {
    RunOptions {
        backend: BackendChoice::Cpu,
        adapter: AdapterChoice::Fallback,
        out_dir: Some(out.to_path_buf()),
        frames: Some(frames),
        progress: false,
        checkpoint_every: None,
        overwrite: false,
    }
}

/// An OBJ as written: `v`, `vn`, `vt`, the groups in order with their faces' fields.
#[derive(Default)]
struct Obj {
    v: Vec<Vec3>,
    vn: Vec<Vec3>,
    vt: usize,
    groups: Vec<(String, Vec<[String; 3]>)>,
}

fn read_obj(path: &Path) -> Obj {
    let text = std::fs::read_to_string(path).unwrap();
    let mut obj = Obj::default();
    let vec3 = |rest: &str| {
        let c: Vec<f32> = rest.split(' ').map(|x| x.parse().unwrap()).collect();
        Vec3::new(c[0], c[1], c[2])
    };
    for line in text.lines() {
        match line.split_once(' ') {
            Some(("v", rest)) => obj.v.push(vec3(rest)),
            Some(("vn", rest)) => obj.vn.push(vec3(rest)),
            Some(("vt", _)) => obj.vt += 1,
            Some(("g", name)) => obj.groups.push((name.to_string(), Vec::new())),
            Some(("f", rest)) => {
                let f: Vec<String> = rest.split(' ').map(String::from).collect();
                obj.groups
                    .last_mut()
                    .expect("faces follow a group")
                    .1
                    .push(<[String; 3]>::try_from(f).expect("triangles"));
            }
            _ => {}
        }
    }
    obj
}

/// Header fields and samples of a PC2 file.
fn read_pc2(path: &Path) -> (i32, f32, f32, Vec<Vec<Vec3>>) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..12], b"POINTCACHE2\0");
    let word = |at: usize| <[u8; 4]>::try_from(&b[at..at + 4]).unwrap();
    assert_eq!(i32::from_le_bytes(word(12)), 1, "version");
    let points = i32::from_le_bytes(word(16)) as usize;
    let (start, rate) = (f32::from_le_bytes(word(20)), f32::from_le_bytes(word(24)));
    let samples = i32::from_le_bytes(word(28));
    assert_eq!(
        b.len(),
        32 + 12 * points * samples as usize,
        "size from the header"
    );
    let f = |at: usize| f32::from_le_bytes(word(at));
    let data = (0..samples as usize)
        .map(|s| {
            (0..points)
                .map(|i| {
                    let at = 32 + 12 * (s * points + i);
                    Vec3::new(f(at), f(at + 4), f(at + 8))
                })
                .collect()
        })
        .collect();
    (samples, start, rate, data)
}

fn outputs(out: &Path) -> Vec<String> {
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let names: Vec<String> = (summary["outputs"].as_array().unwrap().iter())
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    for n in &names {
        assert!(out.join(n).is_file(), "{n} listed but missing");
    }
    names
}

#[test]
fn skirt_on_a_turning_body_exports_obj_body_pc2_and_glb() {
    // The shipped scene asks for pc2 and gltf. Its body turns from 1.5 s; turning from the
    // start lets 5 frames (a few seconds of CPU) see it move. Every 2nd frame: 0, 2, 4 and the
    // last, 5, off the schedule.
    let mut scene = Scene::load(&common::fixture("scenes/skirt_rotating_implicit.toml")).unwrap();
    assert!(scene.output.pc2 && scene.output.gltf);
    let body = &mut scene.bodies[0];
    body.motion = Motion::turn_right_left(60.0, 1.0, 0.0);
    scene.output.every = 2;
    let out = out_dir("skirt");
    run_scene(&scene, &options(&out, 5)).unwrap();
    let prep = prepare(&scene).unwrap();
    let garment = prep.garment.as_ref().unwrap();
    let written = [0u32, 2, 4, 5];
    let names = outputs(&out);
    for f in written {
        let name = format!("frame_{f:04}.obj");
        assert!(names.contains(&name), "{name} not in {names:?}");
    }
    for name in ["cloth.pc2", "garment.glb", "body.obj", "body.glb"] {
        assert!(names.contains(&name.to_string()), "{name} not in {names:?}");
    }
    assert!(
        !names.iter().any(|n| n.starts_with("body_")),
        "a moving body is one mesh, not one per frame: {names:?}"
    );

    // OBJ: one vn and one vt per particle, a group per panel holding that panel's triangles,
    // faces v/vt/vn with one index.
    let frames: Vec<Obj> = (written.iter())
        .map(|f| read_obj(&out.join(format!("frame_{f:04}.obj"))))
        .collect();
    let n = prep.model.len();
    let last = &frames[3];
    assert_eq!((last.v.len(), last.vn.len(), last.vt), (n, n, n));
    let group_names: Vec<&str> = last.groups.iter().map(|g| g.0.as_str()).collect();
    assert_eq!(group_names, garment.panel_names);
    let mut faces = 0;
    for (p, (_, fs)) in last.groups.iter().enumerate() {
        for f in fs {
            let idx: Vec<u32> = (f.iter())
                .map(|c| {
                    let parts: Vec<&str> = c.split('/').collect();
                    assert!(
                        parts.len() == 3 && parts.iter().all(|x| *x == parts[0]),
                        "{c}"
                    );
                    parts[0].parse::<u32>().unwrap() - 1
                })
                .collect();
            assert_eq!(idx, prep.model.triangles[faces], "faces in triangle order");
            assert_eq!(garment.triangle_panel[faces], p as u32);
            faces += 1;
        }
    }
    assert_eq!(faces, prep.model.triangles.len());
    // Unit normals, written to f32's shortest exact digits, so within f32 rounding of 1.
    assert!(last.vn.iter().all(|v| (v.length() - 1.0).abs() < 1e-6));

    // Body: world coordinates at the first frame's time (frame × frame length, as the run
    // loop times frames); the same f32 arithmetic and exact printing give the very same
    // numbers.
    let c = &prep.model.colliders[0];
    let time = |f: u32| f as f32 * prep.frame_dt;
    let pose = c.motion.at(0.0);
    let body = read_obj(&out.join("body.obj"));
    let expected: Vec<Vec3> = (c.body.mesh.positions.iter())
        .map(|p| pose.rotation * *p + pose.translation)
        .collect();
    assert!(body.v == expected, "body at frame 0");
    assert_eq!(body.groups[0].1.len(), c.body.mesh.triangles.len());
    // Its motion: body.glb's node turns with it, a rotation key per written frame equal to
    // the simulation's pose up to sign (q and −q are one rotation).
    let all_times: Vec<f32> = written.iter().map(|&f| time(f)).collect();
    let rotations = body_rotations(&out.join("body.glb"), &all_times);
    for (r, f) in rotations.iter().zip(written) {
        let pose = c.motion.at(time(f)).rotation;
        let r = Quat::from_array(*r);
        assert!(r.dot(pose).abs() > 1.0 - 1e-6, "frame {f}: {r} vs {pose}");
    }
    // The control: it did turn (12.5° by frame 5), so a still pose would fail the above.
    assert!(c.motion.at(time(5)).rotation.angle_between(pose.rotation) > 0.1);

    // PC2: one sample per written frame, equal to the OBJ frame (both hold the f32 exactly).
    let (samples, start, rate, data) = read_pc2(&out.join("cloth.pc2"));
    assert_eq!((samples, start, rate), (4, 0.0, 2.0));
    for (k, frame) in frames.iter().enumerate() {
        assert!(data[k] == frame.v, "sample {k}");
    }

    // glTF: five frames do not sew the skirt, so it holds the panels unwelded from the first
    // simulated frame on (not the flat frame 0), and says so; it validates and reproduces the
    // OBJ frames, with a material per panel.
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["seams_closed_frame"].is_null());
    assert!(s["warnings"]
        .to_string()
        .contains("garment.glb is not welded"));
    let glb = check_glb(
        &out.join("garment.glb"),
        &frames[1..],
        &prep.model.triangles,
        &all_times[1..],
        &garment.panel_names,
    );
    let uv = glb.uv.expect("pattern coordinates");
    for (t, g) in uv.iter().zip(&garment.uv) {
        assert_eq!(*t, [g.x, 1.0 - g.y], "v flipped to glTF's top-left origin");
    }
    // The body node in the garment's file turns too, keyed at its frames.
    let rotations = glb.body_rotations.expect("an animated body");
    assert_eq!(rotations.len(), written.len() - 1);
}

/// The rotation keys of `path`'s body node, keyed at `times`.
fn body_rotations(path: &Path, times: &[f32]) -> Vec<[f32; 4]> {
    khronos_validator(path);
    use gltf::animation::util::{ReadOutputs, Rotations};
    let gltf = gltf::Gltf::from_slice(&std::fs::read(path).unwrap()).expect("a valid glb");
    let blob = gltf.blob.as_deref();
    let body = gltf.nodes().find(|n| n.name() == Some("body")).unwrap();
    assert_eq!(
        body.mesh().unwrap().primitives().count(),
        1,
        "one body mesh"
    );
    let anim = gltf.animations().next().expect("an animation");
    let channel = (anim.channels())
        .find(|c| c.target().property() == gltf::animation::Property::Rotation)
        .expect("a rotation channel");
    let r = channel.reader(|_| blob);
    assert_eq!(r.read_inputs().unwrap().collect::<Vec<_>>(), times);
    match r.read_outputs() {
        Some(ReadOutputs::Rotations(Rotations::F32(r))) => r.collect(),
        _ => panic!("f32 rotations"),
    }
}

#[test]
fn a_grid_on_a_still_body_writes_one_body_and_a_cloth_group() {
    let mut scene = Scene::load(&common::fixture("scenes/drape_sphere.toml")).unwrap();
    scene.output.every = 1;
    scene.output.gltf = true;
    let out = out_dir("sphere");
    run_scene(&scene, &options(&out, 2)).unwrap();
    let names = outputs(&out);
    assert!(names.contains(&"body.obj".into()) && names.contains(&"garment.glb".into()));
    assert!(!names.iter().any(|n| n.starts_with("body_")), "{names:?}");
    assert!(
        !names.contains(&"cloth.pc2".into()),
        "pc2 is off by default"
    );
    let frames: Vec<Obj> = (0..=2)
        .map(|f| read_obj(&out.join(format!("frame_{f:04}.obj"))))
        .collect();
    let f = &frames[2];
    assert_eq!(f.vt, 0);
    assert_eq!(f.groups.len(), 1);
    assert_eq!(f.groups[0].0, "cloth");
    assert!(f.groups[0].1.iter().flatten().all(|c| c.contains("//")));
    let prep = prepare(&scene).unwrap();
    let times = [0.0, prep.frame_dt, 2.0 * prep.frame_dt];
    let glb = check_glb(
        &out.join("garment.glb"),
        &frames,
        &prep.model.triangles,
        &times,
        &["fabric".to_string()],
    );
    assert!(glb.uv.is_none());
    assert!(glb.body_rotations.is_none(), "a still body has no channels");
}

#[test]
fn a_run_that_explodes_keeps_its_frames_in_the_point_cache() {
    // The hanging cloth at one substep per frame, ~200× past its stable step, blows up; the
    // cache holds every frame before the bad one.
    let mut scene = Scene::load(&common::fixture("scenes/hanging_cloth.toml")).unwrap();
    scene.solver.substeps = Some(1);
    scene.output.pc2 = true;
    let out = out_dir("explodes");
    assert!(run_scene(&scene, &options(&out, 72)).is_err());
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let good = summary["frames"].as_u64().unwrap() as usize;
    assert!(summary["error"].is_string() && good < 72, "{summary:#}");
    assert!(outputs(&out).contains(&"cloth.pc2".into()));
    let (samples, _, _, data) = read_pc2(&out.join("cloth.pc2"));
    assert_eq!(samples as usize, good + 1, "frames 0..={good}");
    let last = read_obj(&out.join(format!("frame_{good:04}.obj")));
    assert!(
        data[good] == last.v,
        "the last sample is the last good frame"
    );
}

/// What `check_glb` read beyond its own assertions.
struct Glb {
    uv: Option<Vec<[f32; 2]>>,
    body_rotations: Option<Vec<[f32; 4]>>,
}

/// Parses and validates `path` with the `gltf` crate and checks the garment against the OBJ
/// `frames` written at `times`: base mesh, indices, one morph target per later frame, and a
/// weights animation that selects target k − 1 at frame k.
/// Runs the Khronos glTF validator on `path` when `.ci/run` installed it (it sets
/// `DRAPEKIT_GLTF_VALIDATOR` to the npm package's node_modules); any error fails the test.
fn khronos_validator(path: &Path) {
    let Some(modules) = std::env::var_os("DRAPEKIT_GLTF_VALIDATOR") else {
        eprintln!("the Khronos glTF validator is not installed (see .ci/run): not run");
        return;
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join(".ci/validate_gltf.js");
    let out = std::process::Command::new("node")
        .arg(script)
        .arg(path)
        .env("NODE_PATH", modules)
        .output()
        .expect("node runs");
    let report = String::from_utf8_lossy(&out.stdout);
    eprintln!("{report}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "the glTF validator found errors:\n{report}"
    );
}

fn check_glb(
    path: &Path,
    frames: &[Obj],
    triangles: &[[u32; 3]],
    times: &[f32],
    materials: &[String],
) -> Glb {
    khronos_validator(path);
    use gltf::animation::util::{MorphTargetWeights, ReadOutputs, Rotations};
    let gltf = gltf::Gltf::from_slice(&std::fs::read(path).unwrap()).expect("a valid glb");
    let blob = gltf.blob.as_deref();
    let buffers = |_: gltf::Buffer| blob;
    let node = |name: &str| gltf.nodes().find(|n| n.name() == Some(name));
    let garment = node("garment").expect("a garment node");
    // One primitive and material per panel, in pattern order, sharing the vertices: their
    // indices, one after the other, are the triangles in order (panels are contiguous).
    let prims: Vec<gltf::Primitive> = garment.mesh().unwrap().primitives().collect();
    let names: Vec<String> = (prims.iter())
        .map(|p| p.material().name().unwrap().to_string())
        .collect();
    assert_eq!(names, materials);
    let indices: Vec<u32> = (prims.iter())
        .flat_map(|p| p.reader(buffers).read_indices().unwrap().into_u32())
        .collect();
    assert_eq!(
        indices,
        triangles.iter().flatten().copied().collect::<Vec<_>>()
    );
    let prim = &prims[0];
    let reader = prim.reader(buffers);
    let base: Vec<Vec3> = reader.read_positions().unwrap().map(Vec3::from).collect();
    assert!(base == frames[0].v, "the base mesh is the first frame");
    assert_eq!(reader.read_normals().unwrap().count(), base.len());
    let targets: Vec<Vec<Vec3>> = (reader.read_morph_targets())
        .map(|(p, _, _)| p.unwrap().map(Vec3::from).collect())
        .collect();
    assert_eq!(targets.len(), frames.len() - 1);
    for (k, target) in targets.iter().enumerate() {
        let frame = &frames[k + 1].v;
        for ((d, b), p) in target.iter().zip(&base).zip(frame) {
            // The delta is p − b rounded once to f32 and a viewer adds it back with one more
            // rounding: half an ulp of |p − b| ≤ 2·max(|p|, |b|) plus half an ulp of |p|, at
            // most 1.5·ε·max(|p|, |b|) per coordinate; 2ε leaves a margin.
            let tol = 2.0 * f32::EPSILON * b.abs().max(p.abs());
            let err = (*b + *d - *p).abs();
            assert!(err.cmple(tol).all(), "frame {}: {err} > {tol}", k + 1);
        }
    }
    let anim = gltf.animations().next().expect("an animation");
    let weights = anim
        .channels()
        .find(|c| c.target().property() == gltf::animation::Property::MorphTargetWeights)
        .expect("a weights channel");
    let r = weights.reader(buffers);
    assert_eq!(r.read_inputs().unwrap().collect::<Vec<_>>(), times);
    let Some(ReadOutputs::MorphTargetWeights(MorphTargetWeights::F32(w))) = r.read_outputs() else {
        panic!("f32 weights")
    };
    let w: Vec<f32> = w.collect();
    let n = targets.len();
    assert_eq!(w.len(), n * frames.len());
    for (k, row) in w.chunks(n).enumerate() {
        let hot: Vec<usize> = (0..n).filter(|&i| row[i] != 0.0).collect();
        let expect = if k == 0 { vec![] } else { vec![k - 1] };
        assert_eq!(hot, expect, "weights at frame {k}");
        assert!(hot.iter().all(|&i| row[i] == 1.0));
    }
    let uv = (reader.read_tex_coords(0)).map(|t| t.into_f32().collect());
    let body = node("body").expect("a body node");
    let body_rotations = (anim.channels())
        .find(|c| {
            c.target().node().index() == body.index()
                && c.target().property() == gltf::animation::Property::Rotation
        })
        .map(|c| match c.reader(buffers).read_outputs() {
            Some(ReadOutputs::Rotations(Rotations::F32(r))) => r.collect(),
            _ => panic!("f32 rotations"),
        });
    Glb { uv, body_rotations }
}

#[test]
fn formats_pc2_alone_writes_the_cache_beside_a_rest_obj() {
    let path = common::fixture("scenes/drape_sphere.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replace("obj = true\nevery = 6", "formats = [\"pc2\"]\nevery = 1");
    let scene = Scene::parse(&text, &path).unwrap();
    assert!(!scene.output.obj && scene.output.pc2 && !scene.output.gltf);
    let out = out_dir("formats-pc2");
    run_scene(&scene, &options(&out, 2)).unwrap();
    let names = outputs(&out);
    assert!(names.contains(&"rest.obj".into()) && names.contains(&"cloth.pc2".into()));
    assert!(!names.iter().any(|n| n.starts_with("frame_")), "{names:?}");
    // The rest pose is the first sample, vertex for vertex.
    let rest = read_obj(&out.join("rest.obj"));
    let (samples, _, _, data) = read_pc2(&out.join("cloth.pc2"));
    assert_eq!(samples, 3);
    assert!(data[0] == rest.v);
    // The older switches and the list together are refused, naming the key.
    let both = text.replace("formats = [\"pc2\"]", "formats = [\"pc2\"]\ngltf = true");
    let e = Scene::parse(&both, &path).unwrap_err().to_string();
    assert!(e.contains("output.gltf"), "{e}");
}

#[test]
fn a_sewn_garment_is_one_welded_mesh_in_the_gltf_from_its_first_sewn_frame() {
    // The cotton T-shirt at 5 cm spacing (a 1 cm distance field): its seams close within
    // 21 frames, written every 3rd.
    let path = common::fixture("scenes/tshirt_drape_cotton.toml");
    let mut scene = Scene::load(&path).unwrap();
    if let drapekit::scene::ClothSource::Pattern { options, .. } = &mut scene.cloth {
        options.particle_distance = 0.05;
    }
    scene.bodies[0].sdf_resolution = 0.01;
    scene.output.every = 3;
    scene.output.gltf = true;
    assert!(scene.output.weld_seams, "on by default");
    // The shipped gingham, one copy per 4 cm × 4 cm: the materials' base-colour texture.
    let size_m = [0.04f32, 0.04];
    scene.preview.texture = Some(drapekit::scene::TextureSetting {
        path: common::fixture("textures/gingham.png"),
        size_m,
        pixels: (64, 64),
    });
    let out = out_dir("welded");
    run_scene(&scene, &options(&out, 21)).unwrap();
    let prep = prepare(&scene).unwrap();
    let g = prep.garment.as_ref().unwrap();
    let kept: Vec<u32> = (0..=7).map(|k| 3 * k).collect();
    let frames: Vec<Obj> = (kept.iter())
        .map(|f| read_obj(&out.join(format!("frame_{f:04}.obj"))))
        .collect();
    // The first written frame with every seam closed (the summary's rule), by the test's own
    // reckoning from the OBJ frames.
    let closed = |o: &Obj| {
        let p: Vec<glam::Vec4> = o.v.iter().map(|v| v.extend(0.0)).collect();
        let gaps = drapekit::metrics::seam_gaps(&g.seam_pairs, g.stitches, &p);
        gaps.iter().all(|&gap| gap < prep.seam_closed_gap)
    };
    let start = frames.iter().position(closed).expect("the seams close");
    assert!(
        start > 0 && start + 2 <= frames.len(),
        "sewn at frame {}",
        kept[start]
    );

    // Welding: every seam pair's vertices become one; the garment is one connected mesh.
    let weld = drapekit::pattern::weld::Weld::of_garment(g);
    assert!(weld.len() < prep.model.len());
    let mut parent: Vec<usize> = (0..weld.len()).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            i = p[i];
        }
        i
    }
    for t in &weld.triangles {
        for k in 0..3 {
            let (a, b) = (
                root(&mut parent, t[k] as usize),
                root(&mut parent, t[(k + 1) % 3] as usize),
            );
            parent[a] = b;
        }
    }
    let pieces = (0..weld.len())
        .filter(|&i| root(&mut parent, i) == i)
        .count();
    assert_eq!(pieces, 1, "one connected mesh");
    // Seams closed means every pair within seam_closed_gap_m: a welded vertex (their mean)
    // moves each particle by less than that.
    for f in &frames[start..] {
        assert!(weld.largest_shift(&f.v) < prep.seam_closed_gap);
    }

    // The glTF holds exactly that, from the first sewn frame: welded positions (the mean,
    // rounded once to f32 in the file), the welded triangles by panel.
    let welded: Vec<Obj> = (frames[start..].iter())
        .map(|f| Obj {
            v: weld.positions(&f.v),
            ..Obj::default()
        })
        .collect();
    let times: Vec<f32> = kept[start..]
        .iter()
        .map(|&f| f as f32 * prep.frame_dt)
        .collect();
    let glb = check_glb(
        &out.join("garment.glb"),
        &welded,
        &weld.triangles,
        &times,
        &g.panel_names,
    );
    // Texture coordinates in copies of the image, its top towards each panel's +y (glTF's t
    // runs down the image); the welded vertex takes its first particle's pattern point.
    let uv = glb.uv.expect("texture coordinates");
    for (t, p) in uv.iter().zip(weld.uv(&g.uv)) {
        assert_eq!(*t, [p.x / size_m[0], -p.y / size_m[1]]);
    }
    let gltf = gltf::Gltf::from_slice(&std::fs::read(out.join("garment.glb")).unwrap()).unwrap();
    let png = std::fs::read(common::fixture("textures/gingham.png")).unwrap();
    let image = gltf.images().next().expect("the fabric image");
    let gltf::image::Source::View { view, mime_type } = image.source() else {
        panic!("embedded")
    };
    assert_eq!(mime_type, "image/png");
    let blob = gltf.blob.as_deref().unwrap();
    assert_eq!(
        &blob[view.offset()..view.offset() + view.length()],
        &png[..]
    );
    for m in gltf.materials().filter(|m| m.name() != Some("body")) {
        let info = m
            .pbr_metallic_roughness()
            .base_color_texture()
            .expect("textured");
        assert_eq!(info.texture().source().index(), image.index());
        assert_eq!(m.pbr_metallic_roughness().base_color_factor(), [1.0; 4]);
    }
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        !s["warnings"].to_string().contains("not welded"),
        "{}",
        s["warnings"]
    );
}

#[test]
fn a_deforming_body_is_exported_as_it_moves() {
    // The walking skirt, walking from the start: the body node's mesh is its first exported
    // frame with a morph target per later one, each the body as it stood then.
    let mut scene = Scene::load(&common::fixture("scenes/skirt_walk.toml")).unwrap();
    let deform = scene.bodies[0].deform.as_mut().unwrap();
    (deform.start, deform.transition) = (0.0, 0.0);
    scene.output.gltf = true;
    scene.output.every = 2;
    let out = out_dir("walking-body");
    run_scene(&scene, &options(&out, 4)).unwrap();
    let prep = prepare(&scene).unwrap();
    let collider = &prep.model.colliders[0];
    let gltf = gltf::Gltf::from_slice(&std::fs::read(out.join("garment.glb")).unwrap()).unwrap();
    khronos_validator(&out.join("garment.glb"));
    let blob = gltf.blob.as_deref();
    let buffers = |_: gltf::Buffer| blob;
    let body = gltf.nodes().find(|n| n.name() == Some("body")).unwrap();
    let prim = body.mesh().unwrap().primitives().next().unwrap();
    let reader = prim.reader(buffers);
    let base: Vec<Vec3> = reader.read_positions().unwrap().map(Vec3::from).collect();
    let targets: Vec<Vec<Vec3>> = (reader.read_morph_targets())
        .map(|(p, _, _)| p.unwrap().map(Vec3::from).collect())
        .collect();
    let anim = gltf.animations().next().unwrap();
    let channel = (anim.channels())
        .find(|c| {
            c.target().node().index() == body.index()
                && c.target().property() == gltf::animation::Property::MorphTargetWeights
        })
        .expect("the body's weights channel");
    let times: Vec<f32> = channel.reader(buffers).read_inputs().unwrap().collect();
    // The glTF starts at the first frame with the garment sewn (later than frame 0 here).
    assert!(times.len() >= 2, "times {times:?}");
    assert_eq!(targets.len(), times.len() - 1);
    let mut moved = 0.0f32;
    for (k, &t) in times.iter().enumerate() {
        let expect = collider.world_positions(t);
        for (i, p) in expect.iter().enumerate() {
            let got = base[i]
                + if k == 0 {
                    Vec3::ZERO
                } else {
                    targets[k - 1][i]
                };
            // As for the cloth (check_glb): one rounding of the delta and one of the sum.
            let tol = 2.0 * f32::EPSILON * base[i].abs().max(p.abs());
            assert!(
                (got - *p).abs().cmple(tol).all(),
                "t {t}: vertex {i} {got} != {p}"
            );
            moved = moved.max(p.distance(base[i]));
        }
    }
    eprintln!("body exported at {times:?} s, moving up to {moved:.2e} m from the first");
    assert!(moved > 0.01, "the body hardly moved ({moved} m)");
}
