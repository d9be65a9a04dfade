//! Bodies and collision: mesh checks, the SDF against exact queries, motion, contact
//! strategies, GPU/CPU parity of collide_body, and penetration on drape_sphere.

mod common;

use common::{fixture, gpu, max_abs_diff, Rng};
use drapekit::body::exact::ExactBody;
use drapekit::body::motion::Motion;
use drapekit::body::sdf::Sdf;
use drapekit::body::{brute_query, close_and_orient, shapes, signed_volume, Body};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::GpuSolver;
use drapekit::mesh::TriMesh;
use drapekit::plan::Pass;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, substep_params};
use drapekit::solver::Solver;
use glam::{Vec3, Vec4};

fn random_point(rng: &mut Rng, lo: Vec3, hi: Vec3) -> Vec3 {
    Vec3::new(
        lo.x + (hi.x - lo.x) * rng.unit(),
        lo.y + (hi.y - lo.y) * rng.unit(),
        lo.z + (hi.z - lo.z) * rng.unit(),
    )
}

fn test_bodies() -> Vec<(&'static str, Body)> {
    vec![
        (
            "sphere",
            Body::from_mesh(shapes::sphere(Vec3::new(0.1, 0.2, 0.0), 0.3, 24)).unwrap(),
        ),
        (
            "box",
            Body::from_mesh(shapes::cuboid(Vec3::ZERO, Vec3::new(0.2, 0.1, 0.15))).unwrap(),
        ),
        (
            "capsule",
            Body::from_mesh(shapes::capsule(Vec3::ZERO, 0.1, 0.2, 24)).unwrap(),
        ),
    ]
}

#[test]
fn generated_shapes_are_closed_and_outward() {
    for (name, body) in test_bodies() {
        assert_eq!(body.repairs, Default::default(), "{name} needed repairs");
        assert!(signed_volume(&body.mesh) > 0.0, "{name} is inside out");
    }
}

#[test]
fn open_and_non_manifold_meshes_are_refused_and_flips_repaired() {
    let closed = shapes::cuboid(Vec3::ZERO, Vec3::ONE);
    let mut open = closed.clone();
    open.triangles.pop();
    assert!(close_and_orient(&mut open).unwrap_err().contains("open"));
    let mut fin = closed.clone();
    fin.positions.push(Vec3::new(5.0, 5.0, 5.0));
    fin.triangles.push([0, 2, 8]); // a third face on edge 0–2
    assert!(close_and_orient(&mut fin)
        .unwrap_err()
        .contains("non-manifold"));
    let mut flipped = closed.clone();
    flipped.triangles[3].swap(1, 2);
    flipped.triangles[7].swap(1, 2);
    let r = close_and_orient(&mut flipped).unwrap();
    assert_eq!(r.flipped_faces, 2);
    assert_eq!(flipped.triangles, closed.triangles);
    let mut inside_out: TriMesh = closed.clone();
    for t in &mut inside_out.triangles {
        t.swap(1, 2);
    }
    assert!(
        close_and_orient(&mut inside_out)
            .unwrap()
            .turned_outside_out
    );
    assert!(signed_volume(&inside_out) > 0.0);
}

#[test]
fn each_piece_of_a_body_is_turned_to_face_out() {
    // A large box and, beside it, a small one inside out (a second object of the file): the
    // whole mesh's volume is positive, yet the small piece must be turned too, or its
    // distance field and shading would read it from the inside.
    let mut mesh = shapes::cuboid(Vec3::ZERO, Vec3::ONE);
    let small = shapes::cuboid(Vec3::new(3.0, 0.0, 0.0), Vec3::splat(0.1));
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(&small.positions);
    (mesh.triangles).extend(
        small
            .triangles
            .iter()
            .map(|t| [t[0], t[2], t[1]].map(|i| i + base)),
    );
    assert!(
        signed_volume(&mesh) > 0.0,
        "the whole mesh reads as outward"
    );
    let r = close_and_orient(&mut mesh).unwrap();
    assert!(r.turned_outside_out);
    let piece = TriMesh {
        positions: mesh.positions.clone(),
        triangles: mesh.triangles[12..].to_vec(),
    };
    assert!(signed_volume(&piece) > 0.0, "the small box still faces in");
    assert!(signed_volume(&mesh) > signed_volume(&shapes::cuboid(Vec3::ZERO, Vec3::ONE)));
}

/// A cube exported as a DCC tool writes it: every face with its own texture coordinates, and
/// two objects. OBJ loaders split such vertices; a body welds them back and is closed.
#[test]
fn a_closed_body_with_uv_seams_and_two_objects_loads() {
    let corners = |i: usize| [(i >> 2) & 1, (i >> 1) & 1, i & 1].map(|b| b as f32 * 0.4 - 0.2);
    let faces = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    let write = |faces: &[[usize; 4]]| {
        let mut obj = String::new();
        for i in 0..8 {
            let [x, y, z] = corners(i);
            obj += &format!("v {x} {y} {z}\n");
        }
        for k in 0..24 {
            obj += &format!("vt {} {}\n", k as f32 / 24.0, (k % 4) as f32 / 4.0);
        }
        for (k, f) in faces.iter().enumerate() {
            if k == 3 {
                obj += "o second_half\n";
            }
            let corner = |j: usize| format!("{}/{}", f[j] + 1, 4 * k + j + 1);
            obj += &format!(
                "f {} {} {} {}\n",
                corner(0),
                corner(1),
                corner(2),
                corner(3)
            );
        }
        obj
    };
    let dir = std::env::temp_dir().join(format!("drapekit-uv-cube-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("cube.obj");
    std::fs::write(&path, write(&faces)).unwrap();
    let body = Body::load(&path, 1.0, Vec3::ZERO, "body.path").unwrap();
    assert_eq!(body.mesh.positions.len(), 8, "every corner welded once");
    assert_eq!(body.mesh.triangles.len(), 12);
    // 0.4 m cube: 0.064 m³, exact in f32 to ~1e-8.
    assert!((signed_volume(&body.mesh) - 0.064).abs() < 1e-6);
    // Welding joins only what coincides: a cube missing a face is still open.
    std::fs::write(&path, write(&faces[..5])).unwrap();
    let err = Body::load(&path, 1.0, Vec3::ZERO, "body.path").unwrap_err();
    assert!(err.to_string().contains("open"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sign_is_right_on_points_known_inside_and_outside() {
    for (name, body) in test_bodies() {
        let exact = ExactBody::new(&body.mesh).unwrap();
        let (lo, hi) = bounds(&body.mesh);
        let centre = 0.5 * (lo + hi);
        assert!(exact.query(centre).0 < 0.0, "{name}: centre not inside");
        for dir in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            let far = centre + dir * 2.0 * (hi - lo).length();
            assert!(
                exact.query(far).0 > 0.0,
                "{name}: {dir} far point not outside"
            );
        }
        // Exact and brute force (winding number) agree on sign and distance everywhere.
        let mut rng = Rng::new(11);
        for _ in 0..300 {
            let p = random_point(&mut rng, lo - Vec3::splat(0.05), hi + Vec3::splat(0.05));
            let (a, qa) = exact.query(p);
            let (b, qb) = brute_query(&body.mesh, p);
            assert_eq!(a < 0.0, b < 0.0, "{name}: sign at {p}");
            assert!((a - b).abs() < 1e-6, "{name}: {a} vs {b} at {p}");
            assert!(
                qa.distance(qb) < 1e-5,
                "{name}: nearest {qa} vs {qb} at {p} (d {a})"
            );
        }
    }
}

fn bounds(mesh: &TriMesh) -> (Vec3, Vec3) {
    mesh.positions
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
}

#[test]
fn sdf_matches_exact_queries_within_half_a_cell() {
    for (name, body) in test_bodies() {
        let cell = 0.01;
        let sdf = Sdf::bake(&body, cell, 0.03).unwrap();
        let exact = ExactBody::new(&body.mesh).unwrap();
        let (lo, hi) = bounds(&body.mesh);
        let mut rng = Rng::new(5);
        for _ in 0..2000 {
            let p = random_point(&mut rng, lo - Vec3::splat(0.02), hi + Vec3::splat(0.02));
            let phi = sdf.sample(p).w;
            let (d, _) = exact.query(p);
            // Trilinear interpolation of a 1-Lipschitz function on nodes `cell` apart is off by
            // at most half the cell diagonal's worth in the worst corner; the issue asks for
            // half a cell, which holds away from sharp edges and is what we test.
            assert!(
                (phi - d).abs() <= 0.5 * cell,
                "{name}: φ {phi} vs {d} at {p}"
            );
            if d.abs() > 0.5 * cell {
                assert_eq!(phi < 0.0, d < 0.0, "{name}: sign at {p}");
            }
        }
    }
}

#[test]
fn baked_grids_are_cached_by_mesh_and_resolution() {
    let dir = std::env::temp_dir().join(format!("drapekit-sdf-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let body = &test_bodies()[0].1;
    let (a, ra) = Sdf::bake_cached(body, 0.02, 0.04, Some(&dir)).unwrap();
    let (b, rb) = Sdf::bake_cached(body, 0.02, 0.04, Some(&dir)).unwrap();
    assert!(!ra.from_cache && rb.from_cache);
    assert_eq!(a, b);
    let (_, rc) = Sdf::bake_cached(body, 0.025, 0.04, Some(&dir)).unwrap();
    assert!(!rc.from_cache, "a new resolution is a new bake");
    assert_eq!(ra.bytes, 4 * a.values.len());
    // A damaged cache file is baked again (and rewritten), never read: dims whose product
    // wraps to zero against an empty grid (2³¹ · 2³¹ · 4 = 2⁶⁴), and a NaN among the values.
    let file = std::path::PathBuf::from(ra.cache_file.unwrap());
    let good = std::fs::read(&file).unwrap();
    let mut wrapping = good[..36].to_vec();
    for (k, d) in [1u32 << 31, 1 << 31, 4].iter().enumerate() {
        wrapping[8 + 4 * k..12 + 4 * k].copy_from_slice(&d.to_le_bytes());
    }
    let mut nan = good.clone();
    nan[36..40].copy_from_slice(&f32::NAN.to_le_bytes());
    for damaged in [wrapping, nan] {
        std::fs::write(&file, damaged).unwrap();
        let (c, rd) = Sdf::bake_cached(body, 0.02, 0.04, Some(&dir)).unwrap();
        assert!(!rd.from_cache, "a damaged cache was read");
        assert_eq!(c, a);
        assert_eq!(
            std::fs::read(&file).unwrap(),
            good,
            "the cache was not rewritten"
        );
    }
}

#[test]
fn turn_right_left_motion() {
    let m = Motion::turn_right_left(60.0, 1.0, 0.5);
    let yaw = |t: f32| {
        let (axis, angle) = m.at(t).rotation.to_axis_angle();
        (axis.y.signum() * angle).to_degrees()
    };
    assert!(yaw(0.25).abs() < 1e-4, "still before the start");
    assert!(
        (yaw(1.5) + 60.0).abs() < 1e-3,
        "turned right (negative yaw) at 1.5 s: {}",
        yaw(1.5)
    );
    assert!(
        (yaw(3.5) - 60.0).abs() < 1e-3,
        "turned left at 3.5 s: {}",
        yaw(3.5)
    );
    assert!(yaw(5.0).abs() < 1e-3, "back at 4.5 s");
    // Constant angular speed within a segment: 60° per second about y.
    let w = m.at(1.0).angular_velocity;
    assert!(
        (w - Vec3::new(0.0, -60f32.to_radians(), 0.0)).length() < 1e-4,
        "{w}"
    );
    // A point 1 m from the axis moves at 60°/s · 1 m; one on the axis, 2 m up, not at all:
    // the bound is the distance from the axis, not from the origin.
    let speed = |p: Vec3| m.max_surface_speed(&[p]);
    assert!((speed(Vec3::new(1.0, 0.0, 0.0)) - 60f32.to_radians()).abs() < 1e-4);
    assert!(speed(Vec3::new(0.0, 2.0, 0.0)).abs() < 1e-6);
    assert!((speed(Vec3::new(0.0, 2.0, 1.0)) - 60f32.to_radians()).abs() < 1e-4);
}

/// The drape_sphere scene, with its cloth lowered 5 cm into the sphere's cap, so that ~150
/// particles start inside or within the thickness.
fn touching_sphere() -> drapekit::sim::Prepared {
    let mut scene = Scene::load(&fixture("scenes/drape_sphere.toml")).unwrap();
    if let drapekit::scene::ClothSource::Grid { center, .. } = &mut scene.cloth {
        center.y = 0.25;
    }
    prepare(&scene).unwrap()
}

#[test]
fn parity_collide_body() {
    let Some(ctx) = gpu() else { return };
    let prep = touching_sphere();
    assert!(prep.plan.contains(Pass::CollideBody));
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    // 5 mm and 0.5 m/s perturbations put particles on both sides of the thickness.
    let state = common::perturbed(&cpu.state().unwrap(), 3, 5e-3, 0.5);
    cpu.set_state(&state);
    gpu.set_state(&state);
    let step = substep_params(&prep, 1)[0];
    cpu.run_pass(Pass::CollideBody, &step);
    gpu.run_passes(&[Pass::CollideBody], &[step]).unwrap();
    let g = gpu.state().unwrap();
    let moved = (0..state.positions.len())
        .filter(|&i| cpu.pos[i] != state.positions[i])
        .count();
    assert!(moved > 100, "only {moved} particles collided");
    // Positions are O(0.5 m): one f32 rounding is 3e-8 m; the projection adds a handful of
    // roundings (trilinear φ, normalisation), so 1e-6 m is ample and still far below the
    // millimetre corrections being compared. Velocities are O(1 m/s): the same reasoning.
    let dx = max_abs_diff(&g.positions, &cpu.pos);
    let dv = max_abs_diff(&g.velocities, &cpu.vel);
    assert!(dx <= 1e-6, "positions differ by {dx} m");
    assert!(dv <= 1e-5, "velocities differ by {dv} m/s");
}

#[test]
fn parity_collide_body_with_two_bodies() {
    // The clamp closed 4.5 mm above the table: the kernel reads the clamp's SDF nodes at its
    // offset in the shared texture (the CPU twin has a slice per body), and both take the
    // table, then the clamp, for each particle.
    let Some(ctx) = gpu() else { return };
    let (prep, state, step) = common::pinched();
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    cpu.set_state(&state);
    gpu.set_state(&state);
    cpu.run_pass(Pass::CollideBody, &step);
    gpu.run_passes(&[Pass::CollideBody], &[step]).unwrap();
    let g = gpu.state().unwrap();
    // Where both faces are flat (one 5 mm SDF cell inside their edges) the SDFs are planar and
    // trilinear interpolation is exact, so up to f32 rounding (1e-8 m at these coordinates):
    // under the clamp every particle ends at the clamp's 3 mm thickness below its face (4.5 mm
    // up), whatever the table did first; beside the clamp, on the table, none ends below 3 mm.
    let (clamp, table, thickness, cell) = (0.05f32, 0.1f32, 3e-3f32, 5e-3f32);
    let within = |p: Vec4, half: f32| p.x.abs() < half && p.z.abs() < half;
    let mut under = 0;
    for (i, (start, end)) in state.positions.iter().zip(&cpu.pos).enumerate() {
        if within(*start, clamp - cell) {
            under += 1;
            let y = end.y;
            assert!(
                (y - (4.5e-3 - thickness)).abs() < 1e-6,
                "particle {i} under the clamp at {y} m"
            );
        } else if within(*start, table - cell) && !within(*start, clamp + thickness + cell) {
            let expect = start.y.max(thickness);
            assert!(
                (end.y - expect).abs() < 1e-6,
                "particle {i} beside the clamp at {} m",
                end.y
            );
        }
    }
    // The 14 × 14 grid (2.3 cm apart) puts 4 × 4 particles within 4.5 cm of the centre.
    assert_eq!(under, 16);
    // As parity_collide_body (positions O(0.2 m) here); a body sampled at the wrong nodes
    // would move particles by millimetres.
    let dx = max_abs_diff(&g.positions, &cpu.pos);
    let dv = max_abs_diff(&g.velocities, &cpu.vel);
    assert!(dx <= 1e-6, "positions differ by {dx} m");
    assert!(dv <= 1e-5, "velocities differ by {dv} m/s");
}

/// The touching sphere's cloth moved by up to 5 mm: particles on both sides of the thickness.
fn recorded_state(prep: &drapekit::sim::Prepared) -> drapekit::solver::ParticleState {
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    common::perturbed(&cpu.state().unwrap(), 9, 5e-3, 0.0)
}

#[test]
fn strategies_find_the_same_contacts() {
    let prep = touching_sphere();
    let c = &prep.model.colliders[0];
    let state = recorded_state(&prep);
    let thickness = prep.params.bodies[0].thickness;
    let mut contacts = [Vec::new(), Vec::new(), Vec::new()];
    for (i, p) in state.positions.iter().enumerate() {
        let p = p.truncate();
        let (de, qe) = c.exact.query(p);
        let (db, qb) = brute_query(&c.body.mesh, p);
        let ds = c.sdf.sample(p).w;
        if de < thickness {
            contacts[0].push(i);
            assert!(
                qe.distance(qb) <= 1e-6,
                "particle {i}: nearest points {qe} vs {qb}"
            );
        }
        if db < thickness {
            contacts[1].push(i);
        }
        if ds < thickness {
            contacts[2].push(i);
        }
        // The SDF is within half a cell of the exact distance inside its grid; outside it
        // (the grid spans the body plus a margin above the thickness) it reports no contact.
        if ds == drapekit::body::sdf::SDF_FAR {
            assert!(de > thickness, "particle {i} at {de} m is off the grid");
        } else {
            assert!(
                (ds - de).abs() <= 0.5 * c.sdf.cell,
                "particle {i}: {ds} vs {de}"
            );
        }
    }
    assert!(contacts[0].len() > 100);
    assert_eq!(contacts[0], contacts[1], "exact and brute");
    // The SDF strategy may differ only for particles within half a cell of the threshold.
    for i in contacts[0].iter().filter(|i| !contacts[2].contains(i)) {
        let d = c.exact.query(state.positions[*i].truncate()).0;
        assert!(
            (d - thickness).abs() <= 0.5 * c.sdf.cell,
            "particle {i} at {d}"
        );
    }
}

/// Runs drape_sphere substep by substep and returns the deepest any particle ever got inside
/// the true sphere (the mesh's facets lie inside it, so this bounds the mesh penetration).
fn deepest_inside_sphere(
    solver: &mut dyn Solver,
    prep: &drapekit::sim::Prepared,
    frames: u32,
) -> f32 {
    let mut deepest = 0.0f32;
    for frame in 1..=frames {
        for step in substep_params(prep, frame) {
            solver.advance(&[step]).unwrap();
            let s = solver.state().unwrap();
            for p in &s.positions {
                deepest = deepest.max(0.3 - p.truncate().length());
            }
        }
    }
    deepest
}

#[test]
fn drape_sphere_never_penetrates_more_than_a_millimetre() {
    let mut scene = Scene::load(&fixture("scenes/drape_sphere.toml")).unwrap();
    // 24 frames (1 s): the cloth lands at ~0.26 s and has settled onto the sphere by 1 s.
    scene.solver.frames = 24;
    let prep = prepare(&scene).unwrap();
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let deepest = deepest_inside_sphere(&mut cpu, &prep, 24);
    assert!(deepest <= 1e-3, "cpu: {deepest} m inside");
    if let Some(ctx) = gpu() {
        let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
        let deepest = deepest_inside_sphere(&mut gpu, &prep, 24);
        assert!(deepest <= 1e-3, "gpu: {deepest} m inside");
    }
    // The cloth did reach the sphere: this is not a test of a cloth that never fell.
    let s = cpu.state().unwrap();
    let closest = s
        .positions
        .iter()
        .map(|p| p.truncate().length() - 0.3)
        .fold(f32::MAX, f32::min);
    assert!(
        closest < 0.005,
        "closest particle {closest} m from the sphere"
    );
}

#[test]
fn shipped_mannequins_are_closed_and_their_sign_agrees_with_the_winding_number() {
    for (file, expected_vertices) in [("mannequin.obj", 13380), ("mannequin_lowpoly.obj", 615)] {
        let path = fixture(&format!("bodies/{file}"));
        let body = Body::load(&path, 1.0, Vec3::ZERO, "body.path").unwrap();
        assert_eq!(body.mesh.positions.len(), expected_vertices, "{file}");
        assert!(signed_volume(&body.mesh) > 0.0, "{file}");
        let (lo, hi) = bounds(&body.mesh);
        // A standing adult: 1.6 to 1.8 m tall, in metres.
        assert!(
            (1.6..1.8).contains(&(hi.y - lo.y)),
            "{file}: height {}",
            hi.y - lo.y
        );
        let exact = ExactBody::new(&body.mesh).unwrap();
        let mut rng = Rng::new(17);
        let mut inside = 0;
        for _ in 0..200 {
            let p = random_point(&mut rng, lo, hi);
            // The winding number is 1 inside and 0 outside for a closed mesh; away from the
            // surface it is within 1e-3 of an integer, so 0.5 is an unambiguous threshold.
            let w = drapekit::body::winding_number(&body.mesh, p);
            let (d, _) = exact.query(p);
            if d.abs() > 1e-4 {
                assert_eq!(
                    d < 0.0,
                    w > 0.5,
                    "{file}: at {p}, distance {d}, winding {w}"
                );
            }
            inside += (w > 0.5) as u32;
        }
        assert!(
            inside > 10,
            "{file}: only {inside} of 200 points inside: the test must see both"
        );
    }
}

#[test]
fn bvh_strategies_agree_with_exact_on_a_recorded_state() {
    use drapekit::body::bvh::{BodyBvh, VolumeKind};
    let prep = touching_sphere();
    let c = &prep.model.colliders[0];
    let state = recorded_state(&prep);
    let thickness = prep.params.bodies[0].thickness;
    // The mannequin too: a real, non-convex body with thin parts.
    let mannequin = Body::load(
        &fixture("bodies/mannequin_lowpoly.obj"),
        1.0,
        Vec3::ZERO,
        "b",
    )
    .unwrap();
    let m_exact = ExactBody::new(&mannequin.mesh).unwrap();
    let mut rng = Rng::new(23);
    let (lo, hi) = bounds(&mannequin.mesh);
    let m_points: Vec<Vec3> = (0..400).map(|_| random_point(&mut rng, lo, hi)).collect();
    for kind in [VolumeKind::Aabb, VolumeKind::Obb, VolumeKind::Sphere] {
        let bvh = BodyBvh::new(&c.body.mesh, kind);
        let mut same = 0;
        for (i, p) in state.positions.iter().enumerate() {
            let p = p.truncate();
            let (de, qe) = c.exact.query(p);
            let (db, qb) = bvh.query(p);
            assert_eq!(
                de < thickness,
                db < thickness,
                "{kind:?}: contact of particle {i}"
            );
            if de < thickness {
                same += 1;
                // f32 parry vs f64 reference: both round the nearest point once at ~0.3 m.
                assert!(
                    qe.distance(qb) <= 1e-6,
                    "{kind:?}: particle {i}: {qe} vs {qb}"
                );
            }
        }
        assert!(same > 100, "{kind:?}: only {same} contacts");
        let bvh = BodyBvh::new(&mannequin.mesh, kind);
        for p in &m_points {
            let (de, _) = m_exact.query(*p);
            let (db, _) = bvh.query(*p);
            assert!(
                (de - db).abs() <= 1e-6,
                "{kind:?}: mannequin at {p}: {de} vs {db}"
            );
            if de.abs() > 1e-4 {
                assert_eq!(de < 0.0, db < 0.0, "{kind:?}: mannequin sign at {p}");
            }
        }
    }
}

#[test]
fn rotating_skirt_stays_on_and_out_of_the_mannequin() {
    // The thesis comparison case, full length (5.5 s: sewing, settling, turn right and left),
    // on the CPU path (about 15 s on 2 cores; lavapipe took six times as long). The GPU path
    // runs the same skirt on the same turning body at 720°/s in tests/stability.rs, and its
    // passes follow the CPU's trajectory (tests/parity.rs).
    let scene = Scene::load(&fixture("scenes/skirt_rotating.toml")).unwrap();
    let prep = prepare(&scene).unwrap();
    let c = &prep.model.colliders[0];
    assert!(
        c.motion.max_surface_speed(&[Vec3::X]) > 1.0,
        "the body turns"
    );
    let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = drapekit::sim::RunStats::default();
    let mut lowest_waist = f32::MAX;
    let waist = prep
        .garment
        .as_ref()
        .unwrap()
        .particles_on_labelled_edges(&["lower_interface".to_string()]);
    drapekit::sim::simulate(&prep, &mut solver, &mut stats, |_, s| {
        for &i in &waist {
            lowest_waist = lowest_waist.min(s.positions[i as usize].y);
        }
        Ok(())
    })
    .unwrap();
    let thickness = prep.params.bodies[0].thickness;
    // Measured at every output frame against the exact mannequin mesh.
    assert!(
        stats.max_penetration_m <= thickness,
        "penetration {} m",
        stats.max_penetration_m
    );
    // It stays on the hips (hip line ≈ 0.82 to 0.87 m) through the turns instead of falling.
    assert!(lowest_waist > 0.8, "the waistband fell to {lowest_waist} m");
    // With no strain cap, the seams are closed after the turns, and at the end no edge
    // stretches as far as the old 10% cap: the thesis's pattern, smaller than the hips,
    // stretched its waist 22% and held its side seams 1.5 mm open. Measured: gaps 0.37 and
    // 0.38 mm, the largest strain 7.8% (3.4% at the 99th percentile; 3.2% on lavapipe), the
    // waist no lower than 0.819 m.
    assert!(stats.strain_limit_clamped_edges.is_none(), "the cap is off");
    let gaps = &stats.seam_gaps;
    assert!(
        gaps.iter().all(|&g| g <= prep.seam_closed_gap),
        "seam gaps {gaps:?}"
    );
    assert!(
        stats.last_edge_strain <= 0.1,
        "largest strain {}",
        stats.last_edge_strain
    );
}

/// Whether segment a→b passes through the axis-aligned box `lo`..`hi` (slab test).
fn segment_hits_box(a: Vec3, b: Vec3, lo: Vec3, hi: Vec3) -> bool {
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    let d = b - a;
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (mut ta, mut tb) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        t0 = t0.max(ta);
        t1 = t1.min(tb);
        if t0 > t1 {
            return false;
        }
    }
    true
}

#[test]
fn body_edges_find_the_nearest_edge_of_a_box() {
    // A 4 mm bar along z with its top at y = 0.502; a cloth edge across it 1 mm above the top
    // is 1 mm from both top edges, straight above them.
    let bar = shapes::cuboid(Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.002, 0.002, 0.3));
    let edges = drapekit::body::edges::BodyEdges::new(&bar);
    assert_eq!(
        edges.len(),
        18,
        "a triangulated box has 12 sides and 6 face diagonals"
    );
    let exact = ExactBody::new(&bar).unwrap();
    let inside = |p: Vec3| exact.query(p).0 < 0.0;
    let (a, b) = (Vec3::new(-0.05, 0.503, 0.01), Vec3::new(0.05, 0.503, 0.01));
    let c = edges.deepest(a, b, 0.003, inside).expect("within reach");
    // f32 positions near 0.5 m carry 6e-8 m rounding; the distances are 1 mm.
    assert!((c.distance - 0.001).abs() < 1e-6, "{c:?}");
    assert!(c.normal.distance(Vec3::Y) < 1e-4, "{c:?}");
    assert!((c.point.y - 0.502).abs() < 1e-6 && (c.point.x.abs() - 0.002).abs() < 1e-6);
    // Out of reach: nothing.
    assert!(edges.deepest(a, b, 0.0009, inside).is_none());
    // Through the bar: inside, pushed back out along the edge's outward normal.
    let (a, b) = (Vec3::new(-0.05, 0.5, 0.01), Vec3::new(0.05, 0.5, 0.01));
    let c = edges.deepest(a, b, 0.003, inside).expect("through the bar");
    assert!(c.distance < 0.0, "{c:?}");
}

#[test]
fn an_edge_contact_moves_the_contact_point_out_and_stops_it() {
    use drapekit::body::edges::EdgeContact;
    use drapekit::model::layout::{BodyParams, BodyPose};
    let body = BodyParams {
        thickness: 0.003,
        friction: 0.5,
        ..BodyParams::default()
    };
    let pose = BodyPose {
        x: [1.0, 0.0, 0.0, 0.0],
        y: [0.0, 1.0, 0.0, 0.0],
        z: [0.0, 0.0, 1.0, 0.0],
        ..BodyPose::default()
    };
    // Equal masses; the contact sits a quarter of the way along, touching the body edge.
    let mut pos = vec![
        glam::Vec4::new(0.0, 0.0, 0.0, 10.0),
        glam::Vec4::new(0.04, 0.0, 0.0, 10.0),
    ];
    let mut vel = vec![glam::Vec4::new(0.1, -1.0, 0.0, 0.0); 2];
    let c = EdgeContact {
        s: 0.25,
        point: Vec3::new(0.01, 0.0, 0.0),
        normal: Vec3::Y,
        distance: 0.0,
    };
    drapekit::cpu::collide_edge(&body, &pose, &mut pos, &mut vel, [0, 1], &c);
    let lerp = |v: &[glam::Vec4]| v[0].truncate().lerp(v[1].truncate(), c.s);
    // The contact point ends one thickness out (f32 rounding of mm-sized sums: 1e-9 m).
    assert!((lerp(&pos) - Vec3::new(0.01, 0.003, 0.0)).length() < 1e-9);
    // The ends share the move 3 : 1, like their weights 0.75 and 0.25.
    assert!((pos[0].y / pos[1].y - 3.0).abs() < 1e-5);
    // The contact point's inward speed is gone, and its tangential speed 0.1 m/s drops by
    // μ · 1 m/s = 0.5 m/s, i.e. to 0 (Coulomb, static).
    assert!(lerp(&vel).length() < 1e-6, "{:?}", lerp(&vel));
}

#[test]
fn cloth_edges_catch_on_a_thin_bar_only_with_edge_contacts() {
    // drape_bar.toml: particles 5 cm apart fall onto a 4 mm bar midway between two columns, so
    // no particle ever comes within the thickness of the bar; only edge contacts can hold it.
    let (lo, hi) = (Vec3::new(-0.002, 0.498, -0.3), Vec3::new(0.002, 0.502, 0.3));
    for edge_contacts in [true, false] {
        let mut scene = Scene::load(&fixture("scenes/drape_bar.toml")).unwrap();
        scene.bodies[0].edge_contacts = edge_contacts;
        let prep = prepare(&scene).unwrap();
        let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
        let mut crossing = 0;
        let mut last = Vec::new();
        drapekit::sim::simulate(&prep, &mut cpu, &mut Default::default(), |_, s| {
            let p = |i: u32| s.positions[i as usize].truncate();
            crossing += (prep.model.springs.iter())
                .filter(|sp| segment_hits_box(p(sp.ends[0]), p(sp.ends[1]), lo, hi))
                .count();
            last = s.positions.clone();
            Ok(())
        })
        .unwrap();
        let lowest = last.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        let highest = last.iter().map(|p| p.y).fold(f32::NEG_INFINITY, f32::max);
        if edge_contacts {
            assert_eq!(crossing, 0, "cloth edges passed through the bar");
            // Hanging over the bar: the far columns hang at most half the cloth's width (about
            // 0.2 m, plus 2% stretch) below its top.
            assert!(
                lowest > 0.502 - 0.225 * 1.02 && highest > 0.502,
                "{lowest}..{highest}"
            );
        } else {
            // Without them the cloth falls straight through: 1 s of fall takes it metres down.
            assert!(
                highest < lo.y,
                "the cloth stayed up at {highest} m without edge contacts"
            );
        }
    }
}

#[test]
fn the_built_in_mannequin_is_the_shipped_file_standing_on_its_feet() {
    let feet = Vec3::new(0.1, 0.0, -0.2);
    let built_in = shapes::mannequin(feet);
    let file = TriMesh::load_obj(&fixture("bodies/mannequin.obj"), 1.0, "path").unwrap();
    assert_eq!(built_in.triangles, file.triangles);
    let lowest = file
        .positions
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    let shift = feet - Vec3::new(0.0, lowest, 0.0);
    // One f32 addition of a < 1 m shift to < 1 m coordinates: within 2^-24 · 2 m ≈ 1.2e-7 m.
    for (a, b) in built_in.positions.iter().zip(&file.positions) {
        assert!(a.distance(*b + shift) <= 1.2e-7, "{a} vs {}", *b + shift);
    }
    let lowest_now = (built_in.positions.iter())
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    assert_eq!(lowest_now, feet.y);
    // A scene can ask for it by name.
    let dir = std::env::temp_dir().join(format!("drapekit-mannequin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        "[cloth.grid]\nwidth_m = 0.2\nheight_m = 0.2\ncolumns = 3\nrows = 3\n\
         center_m = [0.0, 1.8, 0.0]\n[fabric]\ndensity_kg_m2 = 0.15\n\
         stretch_stiffness_n_m = 300.0\n[body]\nshape = \"mannequin\"\n[solver]\nframes = 1\n",
    )
    .unwrap();
    let prep = prepare(&Scene::load(&path).unwrap()).unwrap();
    let c = &prep.model.colliders[0];
    assert_eq!(c.body.mesh.positions.len(), 13_380);
}
