//! Collision with a deforming body on the GPU (`kernels/deformed_body.wgsl`) against its CPU
//! twin (`cpu::deformed_sample`) on lavapipe: points around the rigged mannequin mid-walk,
//! through `collide_body` and `contact_planes`, and a short trajectory.

mod common;

use common::{gpu, Rng};
use drapekit::cpu::{collide_body, deformed_sample, DeformedSample};
use drapekit::gpu::implicit::SolveArray;
use drapekit::gpu::GpuSolver;
use drapekit::model::layout::SubstepParams;
use drapekit::plan::{Pass, SolveOp};
use drapekit::scene::Scene;
use drapekit::sim::{part_poses, prepare, substep_params, Prepared};
use drapekit::solver::{ParticleState, Solver};
use glam::{Vec3, Vec4};

/// f32's relative rounding.
const EPS: f32 = f32::EPSILON / 2.0;

/// When the sample is taken: 0.9 s into the walk (its arms swing fastest a quarter cycle in).
const MID_WALK_S: f32 = 0.9;

/// A 48 × 48 grid of cloth (2,304 particles: enough to hold every sample point) beside the
/// walking mannequin, the walk starting at once; `integrator` picks the plan's passes.
fn walking(integrator: &str) -> Prepared {
    walking_with(integrator, 0.0, 0.01)
}

/// `walking`, the walk blended in over `transition_s`, with `sdf_resolution_m` cells.
fn walking_with(integrator: &str, transition_s: f64, sdf_resolution_m: f64) -> Prepared {
    let dir = std::env::temp_dir().join(format!("drapekit-deformed-gpu-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let body = common::Mannequin {
        animation: "walk",
        transition_s,
        sdf_resolution_m,
        friction: None,
    }
    .body_toml();
    let text = format!(
        r#"
[cloth.grid]
width_m = 0.4
height_m = 0.4
columns = 47
rows = 47
center_m = [0.0, 1.9, 0.0]
plane = "xz"

[fabric]
preset = "cotton"

{body}
[solver]
fps = 24
frames = 2
substeps = 4
integrator = "{integrator}"
"#
    );
    let path = dir.join(format!(
        "walking_{integrator}_{transition_s}_{sdf_resolution_m}.toml"
    ));
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path).unwrap();
    prepare(&scene).unwrap()
}

/// The substep's parameters with the parts posed at `t`.
fn step_at(prep: &Prepared, t: f32) -> SubstepParams {
    let mut step = substep_params(prep, 1)[0];
    step.time = t;
    step.parts = part_poses(&prep.model, t);
    step
}

/// Points around the deformed mannequin at `t`: every 7th vertex moved along its normal by a
/// depth from 8 mm inside to 8 mm outside (the shell where collision acts, both sides of the
/// 3 mm thickness), as many as the cloth has particles.
fn points_around(prep: &Prepared, t: f32) -> Vec<Vec3> {
    let c = &prep.model.colliders[0];
    let d = &c
        .deformed
        .as_ref()
        .expect("the mannequin deforms")
        .deformation;
    let posed = d.positions_at(t);
    let normals = drapekit::mesh::vertex_normals(&posed, &c.body.mesh.triangles);
    let mut rng = Rng::new(25);
    let points: Vec<Vec3> = (posed.iter().zip(&normals).step_by(7))
        .map(|(p, n)| *p + 8e-3 * rng.signed() * *n)
        .take(prep.model.len())
        .collect();
    assert!(points.len() > 1000, "only {} points", points.len());
    points
}

/// A state holding `points` (the other particles far above the body) with velocities up to
/// 1 m/s.
fn state_at(prep: &Prepared, points: &[Vec3]) -> ParticleState {
    let mut rng = Rng::new(26);
    let n = prep.model.len();
    ParticleState {
        positions: (0..n)
            .map(|i| {
                points
                    .get(i)
                    .copied()
                    .unwrap_or(Vec3::new(0.0, 3.0, 0.0))
                    .extend(1.0)
            })
            .collect(),
        velocities: (0..n).map(|_| rng.vec3(1.0).extend(0.0)).collect(),
    }
}

/// Whether `got` (φ, normal and the surface velocity at x) is the CPU twin's answer at x within
/// `tol`, or at a point within `reach` of x. The fixed point stops at the first step shorter
/// than SETTLED_STEP, so the two backends may stop one refinement apart, SETTLED_STEP from each
/// other in the rest pose; where that distance crosses a discontinuity of the query (another
/// grid node's nearest triangle, an SDF cell face, a part's box, another part winning, a depth
/// refuted or not), the GPU answers for a neighbour of x, which is what `reach` admits.
fn matches(
    cpu: impl Fn(Vec3) -> DeformedSample,
    x: Vec3,
    got: (f32, Vec3, Vec3),
    tol: (f32, f32, f32),
    reach: f32,
) -> Result<bool, String> {
    let close = |s: DeformedSample| {
        let far = s.phi > 1.0 && got.0 > 1.0;
        far || ((s.phi - got.0).abs() <= tol.0
            && (s.normal - got.1).abs().max_element() <= tol.1
            && (s.velocity_at(x) - got.2).abs().max_element() <= tol.2)
    };
    let here = cpu(x);
    if close(here) {
        return Ok(true);
    }
    let near = (0..27)
        .map(|k| Vec3::new((k % 3) as f32, ((k / 3) % 3) as f32, (k / 9) as f32) - Vec3::ONE)
        .any(|e| close(cpu(x + reach * e)));
    if near {
        return Ok(false);
    }
    Err(format!(
        "at {x}: GPU φ {} n {} v {} vs CPU φ {} n {} v {}",
        got.0,
        got.1,
        got.2,
        here.phi,
        here.normal,
        here.velocity_at(x)
    ))
}

#[test]
fn parity_contact_planes_deforming_body() {
    let Some(ctx) = gpu() else { return };
    let prep = walking("implicit");
    let points = points_around(&prep, MID_WALK_S);
    contact_planes_parity(ctx, &prep, MID_WALK_S, &points, "contact_planes");
}

#[test]
fn parity_contact_planes_at_a_folded_knee() {
    // The pose and the point of tests/joints.rs's folded knee (the walk blended in over 1 s,
    // 5 mm cells): there one part claims the point 3.9 cm deep and another refutes it. A 5 mm
    // grid 3 cm each way around it, as many of its points inside as out.
    let Some(ctx) = gpu() else { return };
    let prep = walking_with("implicit", 1.0, 0.005);
    let t = 3.9566 - 1.5;
    let centre = Vec3::new(0.18510358, 0.40474954, 0.22211906);
    let points: Vec<Vec3> = (0..13 * 13 * 13)
        .map(|k| Vec3::new((k % 13) as f32, ((k / 13) % 13) as f32, (k / 169) as f32))
        .map(|g| centre + 0.005 * (g - Vec3::splat(6.0)))
        .collect();
    contact_planes_parity(ctx, &prep, t, &points, "contact_planes at the folded knee");
}

/// contact_planes on the GPU at `points` (parts posed at `t`, D⁰ = 0) against the CPU's
/// `deformed_sample` there.
fn contact_planes_parity(
    ctx: &'static drapekit::gpu::GpuContext,
    prep: &Prepared,
    t: f32,
    points: &[Vec3],
    stage: &str,
) {
    let step = step_at(prep, t);
    assert!(
        points.len() <= prep.model.len(),
        "more points than particles"
    );
    let state = state_at(prep, points);
    let mut g = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    g.set_state(&state);
    // D⁰ = 0: the plane at each point is (n̂, φ).
    let n = prep.model.len();
    let zero: Vec<Vec4> = state
        .positions
        .iter()
        .map(|p| Vec4::ZERO.with_w(p.w))
        .collect();
    g.set_solve_array(SolveArray::Displacement, &zero).unwrap();
    g.run_solve_ops(&[SolveOp::ContactPlanes], &step).unwrap();
    let planes = g.solve_array(SolveArray::Planes).unwrap();
    let body = prep.params.bodies[0];
    let words = &prep.model.colliders[0].sdf.values;
    let cpu = |x: Vec3| deformed_sample(&body, &step.parts, words, x);
    let (tol, reach) = tolerances(prep.model.colliders[0].sdf.cell);
    let (mut exact, mut neighbour, mut inside) = (0, 0, 0);
    let (mut dphi, mut dn) = (0.0f32, 0.0f32);
    for (i, x) in points.iter().enumerate().take(n) {
        let p = planes[i];
        let s = cpu(*x);
        inside += (s.phi < 0.0) as usize;
        // contact_planes carries no velocity: compare the CPU's own.
        let got = (p.w, p.truncate(), s.velocity_at(*x));
        match matches(cpu, *x, got, tol, reach) {
            Ok(true) => {
                exact += 1;
                if s.phi < 1.0 {
                    dphi = dphi.max((s.phi - p.w).abs());
                    dn = dn.max((s.normal - p.truncate()).abs().max_element());
                }
            }
            Ok(false) => neighbour += 1,
            Err(e) => panic!("{stage}, point {i} {e}"),
        }
    }
    eprintln!("{stage}: largest differences φ {dphi:.2e} m, normal {dn:.2e}");
    report_counts(stage, exact, neighbour, inside, points.len());
}

#[test]
fn parity_collide_body_deforming_body() {
    let Some(ctx) = gpu() else { return };
    let mut prep = walking("symplectic");
    assert!(prep.plan.contains(Pass::CollideBody));
    // A 1 cm layer: every sample point within it is moved out, so that the moved position
    // shows φ and the normal: x' − x = (thickness − φ)·n̂.
    prep.params.bodies[0].thickness = 0.01;
    let step = step_at(&prep, MID_WALK_S);
    let points = points_around(&prep, MID_WALK_S);
    let state = state_at(&prep, &points);
    let mut g = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    g.set_state(&state);
    g.run_passes(&[Pass::CollideBody], &[step]).unwrap();
    let got = g.state().unwrap();
    let (mut pos, mut vel) = (state.positions.clone(), state.velocities.clone());
    let words: Vec<&[f32]> = vec![&prep.model.colliders[0].sdf.values[..]];
    collide_body(
        &prep.params,
        &step,
        &mut pos,
        &mut vel,
        1,
        &words,
        |_, _| unreachable!("the only body deforms"),
    );
    let body = prep.params.bodies[0];
    let cpu_sample = |x: Vec3| deformed_sample(&body, &step.parts, words[0], x);
    let (tol, reach) = tolerances(prep.model.colliders[0].sdf.cell);
    let (mut exact, mut neighbour, mut inside) = (0, 0, 0);
    let (mut moved, mut dx_max, mut dv_max) = (0, 0.0f32, 0.0f32);
    for (i, x) in points.iter().enumerate() {
        let (gx, gv) = (got.positions[i].truncate(), got.velocities[i].truncate());
        let (cx, cv) = (pos[i].truncate(), vel[i].truncate());
        let push = gx - *x;
        let s = cpu_sample(*x);
        inside += (s.phi < 0.0) as usize;
        if push.length() == 0.0 || (cx - *x).length() == 0.0 {
            // One backend left it: it saw φ ≥ the thickness (or no part), so the other must
            // have seen φ within the φ bound of it, or answered for a neighbour.
            let edge = s.phi > 1.0 || s.phi >= body.thickness - tol.0;
            let near = edge || neighbour_left(cpu_sample, *x, body.thickness, reach);
            assert!(
                near,
                "point {i} at {x}: GPU moved {push}, CPU moved {}, φ {}",
                cx - *x,
                s.phi
            );
            neighbour += (push.length() != (cx - *x).length()) as usize;
            continue;
        }
        moved += 1;
        // φ and the normal from the push (the velocity through the response is compared
        // below, as each backend computes it).
        let phi = body.thickness - push.length();
        let normal = push / push.length();
        let agrees = matches(cpu_sample, *x, (phi, normal, s.velocity_at(*x)), tol, reach);
        match agrees {
            Ok(true) => {
                exact += 1;
                dx_max = dx_max.max((gx - cx).abs().max_element());
                dv_max = dv_max.max((gv - cv).abs().max_element());
            }
            Ok(false) => neighbour += 1,
            Err(e) => panic!("collide_body, point {i} {e}"),
        }
    }
    eprintln!("collide_body: largest differences x {dx_max:.2e} m, v {dv_max:.2e} m/s");
    report_counts("collide_body", exact, neighbour, inside, points.len());
    assert!(moved > points.len() / 2, "only {moved} points moved");
    // Where both answered for x itself: the position is x + (thickness − φ)·n̂, so it differs
    // by the φ bound plus the normal bound times the push (≤ 1.8 cm), and the velocity by the
    // velocity bound plus the normal bound times the speeds involved (≤ 1 m/s + the surface's
    // ≤ 3 m/s), through the Coulomb scale's division by the tangential speed (bounded by one
    // more such term).
    let (tol_phi, tol_n, tol_v) = tol;
    let dx_bound = tol_phi + tol_n * 0.018 + 4.0 * EPS * 2.0;
    let dv_bound = tol_v + 2.0 * tol_n * 4.0;
    assert!(
        dx_max <= dx_bound,
        "positions differ by {dx_max} m (bound {dx_bound})"
    );
    assert!(
        dv_max <= dv_bound,
        "velocities differ by {dv_max} m/s (bound {dv_bound})"
    );
}

/// Whether the CPU leaves a neighbour of x within `reach` alone (φ ≥ `thickness` there).
fn neighbour_left(
    cpu: impl Fn(Vec3) -> DeformedSample,
    x: Vec3,
    thickness: f32,
    reach: f32,
) -> bool {
    (0..27)
        .map(|k| Vec3::new((k % 3) as f32, ((k / 3) % 3) as f32, (k / 9) as f32) - Vec3::ONE)
        .any(|e| cpu(x + reach * e).phi >= thickness)
}

/// (φ in m, normal, surface velocity in m/s) bounds, and the reach of a neighbour.
///
/// The two backends refine the rest point y with the same f32 operations; they differ by
/// rounding (a few ε of coordinates ≤ 2 m, ~1e-6 m, negligible) and by when they stop: each
/// stops at its first step shorter than SETTLED_STEP (1e-5 m), and rounding can make one take
/// one more, so their y differ by at most SETTLED_STEP. From there:
/// - φ, trilinear in y with a gradient of length ≤ ~1.5 (near a node where the distance field
///   bends), moves by ≤ 1.5·SETTLED_STEP, plus the interpolation's rounding (a few ε of node
///   values ≤ 1 m): 2e-5 m bounds it;
/// - the trilinear gradient changes within a cell by at most ~2 (its value across a cell at a
///   sharp crease) over the `cell`, so by 2·SETTLED_STEP/cell for that shift (2e-3 at 1 cm,
///   4e-3 at 5 mm), and A⁻ᵀ turns it by what the skin weights change: their barycentric
///   coordinates move by SETTLED_STEP over a rest edge (≥ 5 mm), 2e-3, times the parts'
///   rotations' differences (≤ 2): 4e-3; together 6e-3 (1 cm) or 8e-3 (5 mm) on a unit normal;
/// - the blended surface velocity changes by the same 2e-3 of the weights times the parts'
///   velocities' spread (the walk's limbs move at ≤ 3 m/s against the torso): 6e-3 m/s.
///
/// Where the SETTLED_STEP shift crosses a discontinuity, the neighbour within 2·SETTLED_STEP
/// (x moves y about one to one: the parts are rigid) is what the GPU answered for.
fn tolerances(cell: f32) -> ((f32, f32, f32), f32) {
    let settled = drapekit::cpu::SETTLED_STEP;
    let normal = 2.0 * settled / cell + 4e-3;
    ((2e-5, normal, 6e-3), 2.0 * settled)
}

/// Prints the counts and checks that answers for a neighbour stay rare: a discontinuity is
/// within 2·SETTLED_STEP of a point with a probability of about that over the features' spacing
/// (~4e-3 per kind of feature over a 5 mm–1 cm spacing, a handful of kinds).
fn report_counts(stage: &str, exact: usize, neighbour: usize, inside: usize, total: usize) {
    eprintln!(
        "{stage}: {exact} points as the CPU, {neighbour} as the CPU at a neighbour, \
         {inside} of {total} inside the body"
    );
    assert!(inside > total / 5, "{stage}: only {inside} points inside");
    assert!(
        neighbour * 20 <= exact + neighbour,
        "{stage}: {neighbour} of {} points differ from the CPU at x itself",
        exact + neighbour
    );
}

/// A 10 cm patch of cotton dropped on the left shoulder as the walk starts, 12 frames
/// (0.5 s) of implicit Euler on each backend.
fn shoulder_patch() -> Prepared {
    let dir = std::env::temp_dir().join(format!("drapekit-deformed-gpu-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The shoulder's top is at y ≈ 1.38 m, 14 cm left of the axis.
    let body = common::Mannequin {
        animation: "walk",
        transition_s: 0.2,
        sdf_resolution_m: 0.01,
        friction: Some(0.4),
    }
    .body_toml();
    let text = format!(
        r#"
[cloth.grid]
width_m = 0.1
height_m = 0.1
columns = 10
rows = 10
center_m = [0.14, 1.40, 0.0]
plane = "xz"

[fabric]
preset = "cotton"

{body}
[solver]
fps = 24
frames = 12
substeps = 8
iterations = 3
integrator = "implicit"
"#
    );
    let path = dir.join("shoulder_patch.toml");
    std::fs::write(&path, text).unwrap();
    prepare(&Scene::load(&path).unwrap()).unwrap()
}

#[test]
fn trajectory_on_a_walking_shoulder_gpu() {
    use drapekit::cpu::CpuSolver;
    use drapekit::sim::{simulate, RunStats};
    let Some(ctx) = gpu() else { return };
    let prep = shoulder_patch();
    let run = |solver: &mut dyn Solver| {
        let mut frames = Vec::new();
        let mut stats = RunStats::default();
        simulate(&prep, solver, &mut stats, |_, s| {
            frames.push(s.positions.clone());
            Ok(())
        })
        .unwrap();
        (frames, stats)
    };
    let substeps = prep.substeps as usize;
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, substeps).unwrap();
    let (g_frames, g_stats) = run(&mut gpu);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let (c_frames, c_stats) = run(&mut cpu);
    let deepest = |s: &RunStats| {
        (s.deformed_penetration_m.iter())
            .map(|(_, d)| *d)
            .fold(0.0f32, f32::max)
    };
    let thickness = prep.params.bodies[0].thickness;
    eprintln!(
        "deepest inside the deformed mesh: GPU {:.2e} m, CPU {:.2e} m over {} frames",
        deepest(&g_stats),
        deepest(&c_stats),
        g_stats.deformed_penetration_m.len()
    );
    assert_eq!(g_stats.deformed_penetration_m.len(), g_frames.len() - 1);
    // The issue's criterion, on the GPU path: no particle deeper than the thickness inside the
    // exact deformed mesh at any output frame.
    assert!(deepest(&g_stats) <= thickness, "GPU: {}", deepest(&g_stats));
    // The patch rides the shoulder: at the end it lies over it, its middle (a quarter of it
    // and more) touching the body while its edges hang.
    let n = prep.model.len();
    eprintln!(
        "GPU: {} of {n} particles touch the body at the end",
        g_stats.body_contacts
    );
    assert!(
        g_stats.body_contacts >= n / 4,
        "{} touch",
        g_stats.body_contacts
    );
    // And the backends agree: they round differently (~1e-7 m per substep), which alone would
    // stay far below a millimetre over 96 substeps; what can grow is a particle that one backend
    // finds inside the contact layer a substep before the other, which moves it by at most the
    // layer's depth. So no particle may end further apart than the thickness.
    let centroid = |f: &[Vec4]| f.iter().map(|p| p.truncate()).sum::<Vec3>() / f.len() as f32;
    let (g_end, c_end) = (g_frames.last().unwrap(), c_frames.last().unwrap());
    let apart = centroid(g_end).distance(centroid(c_end));
    let worst = common::max_abs_diff(g_end, c_end);
    eprintln!("end: centroids {apart:.2e} m apart, particles at most {worst:.2e} m");
    assert!(worst <= thickness, "particles end {worst} m apart");
}

/// A 10 cm cotton patch resting on a 20 cm box that a vertex cache (one collision part)
/// slides 10 cm along x over 1 s from 0.25 s; implicit Euler with friction 0.8.
fn sliding_box() -> Prepared {
    let dir = std::env::temp_dir().join(format!("drapekit-sliding-box-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (text, corners) = common::box_obj(0.1);
    std::fs::write(dir.join("box.obj"), text).unwrap();
    let moved: Vec<Vec3> = corners.iter().map(|p| *p + SLIDE).collect();
    let bytes = drapekit::export::pc2::pc2_bytes(&[corners, moved], 0.0, 1.0).unwrap();
    std::fs::write(dir.join("box.pc2"), bytes).unwrap();
    let scene = r#"
[cloth.grid]
width_m = 0.1
height_m = 0.1
columns = 10
rows = 10
center_m = [0.0, 0.104, 0.0]
plane = "xz"

[fabric]
preset = "cotton"

[body]
path = "box.obj"
cache = "box.pc2"
cache_fps = 1.0
parts = 1
motion_start_s = 0.25
transition_s = 0.0
thickness_m = 0.003
sdf_resolution_m = 0.01
sdf_cache = false
friction = 0.8

[world]
gravity_m_s2 = [0.0, -9.81, 0.0]

[solver]
fps = 24
frames = 24
substeps = 4
integrator = "implicit"
"#;
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    prepare(&Scene::load(&path).unwrap()).unwrap()
}

/// How far the box slides over its second of motion.
const SLIDE: Vec3 = Vec3::new(0.1, 0.0, 0.0);

/// The patch's slip over the box from the motion's start (frame 6, 0.25 s) to frame 24 (1 s),
/// along x, in m.
fn slip_on_sliding_box(prep: &Prepared, solver: &mut dyn Solver) -> f32 {
    use drapekit::sim::{simulate, RunStats};
    let mut centroid_x = Vec::new();
    simulate(prep, solver, &mut RunStats::default(), |_, s| {
        let sum: f32 = s.positions.iter().map(|p| p.x).sum();
        centroid_x.push(sum / s.positions.len() as f32);
        Ok(())
    })
    .unwrap();
    let box_moved = SLIDE.x * (1.0 - 0.25);
    (centroid_x[24] - centroid_x[6]) - box_moved
}

#[test]
fn implicit_friction_carries_cloth_with_the_skin() {
    let prep = sliding_box();
    assert_eq!(prep.params.bodies[0].parts, 1);
    // Friction measured against the skin's velocity carries the patch: it slips only while it
    // catches up with the box at the start, v²/(2μg) = 0.64 mm at full Coulomb friction, plus
    // v·ε_v/(μg) = 0.13 mm while static friction (proportional to the slip below ε_v =
    // 0.01 m/s) holds it, plus one substep of the box's travel (1 mm: the surface velocity is
    // taken at the step's start). Against the body's root, which stands still, the box would
    // slide 75 mm under the patch.
    let (v, mu, g) = (SLIDE.x, 0.8, 9.81);
    let bound = v * v / (2.0 * mu * g) + v * 0.01 / (mu * g) + v * prep.params.dt;
    let mut cpu = drapekit::cpu::CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let cpu_slip = slip_on_sliding_box(&prep, &mut cpu);
    eprintln!("CPU: slip {cpu_slip:.2e} m (bound {bound:.2e} m)");
    assert!(
        cpu_slip.abs() <= bound,
        "CPU: the patch slipped {cpu_slip} m"
    );
    let Some(ctx) = gpu() else { return };
    let substeps = prep.substeps as usize;
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, substeps).unwrap();
    let gpu_slip = slip_on_sliding_box(&prep, &mut gpu);
    eprintln!("GPU: slip {gpu_slip:.2e} m (bound {bound:.2e} m)");
    assert!(
        gpu_slip.abs() <= bound,
        "GPU: the patch slipped {gpu_slip} m"
    );
}
