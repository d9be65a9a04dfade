//! GPU vs CPU: each pass from one identical state, and whole trajectories of the hanging cloth
//! (with edge springs, and as an orthotropic membrane).

mod common;

use common::{fixture, gpu, max_abs_diff, max_norm, on_fallback, perturbed};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::GpuSolver;
use drapekit::model::layout::{SubstepParams, INTEGRATOR_EXPLICIT, INTEGRATOR_SYMPLECTIC};
use drapekit::plan::{HingeEvaluation, Pass};
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, substep_params, Prepared, RunStats};
use drapekit::solver::{ParticleState, Solver};

/// The flag scene (springs, bending, wind: every pass) from a perturbed state.
fn flag() -> Prepared {
    let scene = Scene::load(&fixture("scenes/flag_wind.toml")).unwrap();
    prepare(&scene).unwrap()
}

fn pass_parity(pass: Pass) {
    pass_parity_in(flag(), pass);
}

fn pass_parity_in(prep: Prepared, pass: Pass) {
    let Some(ctx) = gpu() else { return };
    // Both backends run the same stages (each would otherwise evaluate hinges its own way).
    let plan = prep.plan.with_hinges(match pass {
        Pass::BendingForces => HingeEvaluation::PerVertex,
        _ => HingeEvaluation::Once,
    });
    assert!(plan.contains(pass));
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &plan, 1).unwrap();
    // 5 mm and 0.5 m/s perturbations give every spring, hinge and triangle a non-trivial force.
    let state = perturbed(&cpu.state().unwrap(), 7, 5e-3, 0.5);
    cpu.set_state(&state);
    gpu.set_state(&state);
    let step: SubstepParams = substep_params(&prep, 3)[5];
    cpu.run_pass(pass, &step);
    gpu.run_passes(&[pass], &[step]).unwrap();
    if pass == Pass::Integrate {
        // Forces are zero here, so integrate adds dt·(g − γv) to v and dt·v to x. Positions are
        // O(2 m) and f32 has a 2^-24 relative step: one rounding of each term gives ≤ 4e-7 m,
        // and FMA contraction on the GPU may differ by one such rounding (on any adapter:
        // integrate divides by nothing, so WGSL's 2.5-ULP division does not enter).
        let g = gpu.state().unwrap();
        let dx = max_abs_diff(&g.positions, &cpu.pos);
        let dv = max_abs_diff(&g.velocities, &cpu.vel);
        assert!(dx <= 4e-7, "positions differ by {dx} m");
        assert!(dv <= 4e-7, "velocities differ by {dv} m/s");
    } else if pass == Pass::StrainLimit {
        // Each of the `strain_iterations` Jacobi iterations adds to a position O(2 m) the mean
        // of ≤ 6 corrections share·(|d| − L)·d/|d|; the cancellation in |d| − L carries a
        // relative 2e-6 of each correction (as for springs below), and storing p + Δ rounds by
        // 2^-24·2 m ≈ 1.2e-7 m. So per iteration ≤ 1.2e-7 m + 2e-6·max|Δ|, and the velocity
        // (v + Δ/h) differs by that over h plus the rounding of v itself.
        let g = gpu.state().unwrap();
        let moved = (cpu.pos.iter().zip(&state.positions))
            .map(|(a, b)| (*a - *b).truncate().length())
            .fold(0.0f32, f32::max);
        assert!(moved > 1e-4, "strain_limit moved nothing ({moved} m)");
        let k = prep.params.strain_iterations as f32;
        let dx_bound = k * (1.2e-7 + 2e-6 * moved);
        let v_scale = max_norm(&cpu.vel);
        let dv_bound = dx_bound / prep.params.dt + k * 1.2e-7 * v_scale;
        let dx = max_abs_diff(&g.positions, &cpu.pos);
        let dv = max_abs_diff(&g.velocities, &cpu.vel);
        assert!(
            dx <= dx_bound,
            "positions differ by {dx} m (bound {dx_bound})"
        );
        assert!(
            dv <= dv_bound,
            "velocities differ by {dv} m/s (bound {dv_bound})"
        );
    } else {
        // Each force is a sum of up to ~12 terms, each a product of a few f32 operations. The
        // worst amplification is the cancellation in (|d| − L0): |d| ≈ 3 cm carries a rounding of
        // 2^-24·3 cm ≈ 2e-9 m against stretches of ~1 mm, a relative 2e-6 of the term. So the
        // two backends may differ by a few 1e-6 of the largest force; 2e-5 leaves 10× margin.
        // The bound holds on any conforming adapter: a 2.5-ULP division or `inverseSqrt`
        // (1.5e-7 relative) and FMA contraction (half an ULP per a·b + c) add far less than the
        // cancellation's 2e-6.
        let f_gpu = gpu.forces().unwrap();
        let scale = max_norm(&cpu.force);
        assert!(scale > 0.0, "{} produced no force", pass.name());
        let diff = max_abs_diff(&f_gpu, &cpu.force);
        assert!(
            diff <= 2e-5 * scale,
            "{}: max diff {diff} N vs max force {scale} N",
            pass.name()
        );
    }
}

#[test]
fn parity_spring_forces() {
    pass_parity(Pass::SpringForces);
}

/// The flag with springs that buckle: perturbed by 5 mm, a good share of its springs are
/// compressed past their Euler onset (a micrometre or so), where the buckled branch of the
/// law carries their force. The bound is `pass_parity_in`'s: the buckled tension
/// −k·o + r·k·(s + o) carries the same relative rounding of s as k·s does.
#[test]
fn parity_spring_forces_buckling() {
    let scene = common::scene_with_fabric("scenes/flag_wind.toml", common::BUCKLING);
    let prep = prepare(&scene).unwrap();
    assert!(prep.params.buckled_fraction > 0.0 && prep.params.euler_onset > 0.0);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let state = perturbed(&cpu.state().unwrap(), 7, 5e-3, 0.5);
    let buckled = common::buckled_springs(&prep, &state.positions);
    assert!(
        buckled * 5 > prep.model.springs.len(),
        "only {buckled} of {} springs buckled",
        prep.model.springs.len()
    );
    pass_parity_in(prep, Pass::SpringForces);
}

#[test]
fn parity_bending_forces() {
    pass_parity(Pass::BendingForces);
}

/// `hinge_forces` alone: each hinge's four forces, compared entry by entry. Each entry is one
/// evaluation of a few f32 operations whose worst amplification is the cancellation in
/// sin(θ/2) − sin(θ0/2) of a nearly flat hinge: such a hinge's force is small, so relative to
/// the largest entry the backends differ by about 1e-6 (the force bound below, 2e-5, leaves
/// 10× margin). Then `integrate` gathers these entries (`parity_integrate_gathers_bending`).
#[test]
fn parity_hinge_forces() {
    let Some(ctx) = gpu() else { return };
    let prep = flag();
    let plan = prep.plan.with_hinges(HingeEvaluation::Once);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &plan, 1).unwrap();
    let state = perturbed(&cpu.state().unwrap(), 7, 5e-3, 0.5);
    cpu.set_state(&state);
    gpu.set_state(&state);
    let step: SubstepParams = substep_params(&prep, 3)[5];
    cpu.run_pass(Pass::HingeForces, &step);
    gpu.run_passes(&[Pass::HingeForces], &[step]).unwrap();
    let c = cpu.hinge_forces().unwrap();
    let g = gpu.hinge_forces().unwrap();
    assert_eq!(c.len(), 4 * prep.model.hinges.len());
    let scale = max_norm(c);
    assert!(scale > 0.0, "hinge_forces produced no force");
    let diff = max_abs_diff(&g, c);
    assert!(
        diff <= 2e-5 * scale,
        "hinge_forces: max diff {diff} N vs max force {scale} N"
    );
}

/// `hinge_forces` then `integrate`, which gathers the hinge forces per particle: velocities
/// change by dt·f/m. The gathered force may differ by 2e-5 of the largest per-particle bending
/// force (12 terms, each within the `parity_hinge_forces` bound), so the velocities may differ
/// by dt·max(1/m)·2e-5·max|f| plus the 4e-7 rounding of `parity_integrate`, and positions by dt
/// times that plus their own 4e-7.
#[test]
fn parity_integrate_gathers_bending() {
    let Some(ctx) = gpu() else { return };
    let prep = flag();
    let plan = prep.plan.with_hinges(HingeEvaluation::Once);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &plan, 1).unwrap();
    let state = perturbed(&cpu.state().unwrap(), 7, 5e-3, 0.5);
    cpu.set_state(&state);
    gpu.set_state(&state);
    let step: SubstepParams = substep_params(&prep, 3)[5];
    for pass in [Pass::HingeForces, Pass::Integrate] {
        cpu.run_pass(pass, &step);
        gpu.run_passes(&[pass], &[step]).unwrap();
    }
    // The largest bending force on a particle, from the CPU's per-hinge forces.
    let forces = cpu.hinge_forces().unwrap();
    let csr = prep.model.hinge_csr();
    let bending = (0..prep.model.len())
        .map(|i| {
            (csr.offsets[i]..csr.offsets[i + 1])
                .map(|k| forces[csr.items[k as usize] as usize].truncate())
                .sum::<glam::Vec3>()
                .length()
        })
        .fold(0.0f32, f32::max);
    assert!(bending > 0.0, "no bending force");
    let max_inv_mass = state.positions.iter().map(|p| p.w).fold(0.0f32, f32::max);
    let dt = prep.params.dt;
    let dv_bound = dt * max_inv_mass * 2e-5 * bending + 4e-7;
    let dx_bound = dt * dv_bound + 4e-7;
    // The step must move the velocities by much more than the bound, or it shows nothing.
    let kick = dt * max_inv_mass * bending;
    assert!(
        kick > 100.0 * dv_bound,
        "bending kick {kick} m/s vs bound {dv_bound}"
    );
    let g = gpu.state().unwrap();
    let dv = max_abs_diff(&g.velocities, &cpu.vel);
    let dx = max_abs_diff(&g.positions, &cpu.pos);
    assert!(
        dv <= dv_bound,
        "velocities differ by {dv} m/s (bound {dv_bound})"
    );
    assert!(
        dx <= dx_bound,
        "positions differ by {dx} m (bound {dx_bound})"
    );
}

#[test]
fn parity_wind_forces() {
    pass_parity(Pass::WindForces);
}

#[test]
fn parity_seam_forces() {
    // The T-shirt pattern as placed: every seam pair is ~10 to 30 cm apart, so every pair pulls.
    // Its seam forces are sums of ≤ 6 terms k·(x_p − x_a), whose cancellation is mild; the
    // force tolerance below covers them as it covers springs.
    let scene = Scene::load(&fixture("scenes/tshirt_sew.toml")).unwrap();
    pass_parity_in(prepare(&scene).unwrap(), Pass::SeamForces);
}

#[test]
fn parity_seam_forces_while_sewing() {
    // With a 100 s sewing time every rest gap is still ~99.9% of its placed gap at this step,
    // so the 5 mm perturbation leaves about half the pairs inside their rest gap (no spring)
    // and half outside it: both branches of the rest-gap force run.
    let mut scene = Scene::load(&fixture("scenes/tshirt_sew.toml")).unwrap();
    if let drapekit::scene::ClothSource::Pattern { sewing_time, .. } = &mut scene.cloth {
        *sewing_time = 100.0;
    }
    let prep = prepare(&scene).unwrap();
    assert!(prep.model.seams.iter().all(|s| s.open_gap > 0.05));
    pass_parity_in(prep, Pass::SeamForces);
}

/// The hanging cloth as an orthotropic membrane (warp 300, weft 150, shear 30 N/m) whose warp
/// runs at 30° to the grid's rows: every triangle's warp and weft images are oblique, so all
/// three conditions pull on every vertex. 100 substeps a frame: about the automatic step at
/// 16×16 (97 with 300 N/m springs, 94 as this membrane), fixed so that the run does not follow
/// the stable-step estimate.
fn membrane_sheet(columns: u32) -> Scene {
    let mut scene = common::scene_with_fabric(
        "scenes/hanging_cloth.toml",
        "model = \"membrane\"\nwarp_stiffness_n_m = 300.0\nweft_stiffness_n_m = 150.0\n\
         shear_stiffness_n_m = 30.0\ngrain_deg = 30.0",
    );
    if let drapekit::scene::ClothSource::Grid {
        columns: c, rows, ..
    } = &mut scene.cloth
    {
        (*c, *rows) = (columns, columns);
    }
    scene.solver.substeps = Some(100);
    scene
}

#[test]
fn parity_membrane_forces() {
    // A membrane force on a vertex sums ≤ 6 triangles' three conditions. The images w are
    // differences of nearby positions (exact in f32) times coefficients ~1/edge, so each
    // carries a few roundings relative to |w| ≈ 1, and |w| − 1 a few ε ≈ 1e-7 absolute against
    // the 5 mm perturbation's strains of ~0.1: a relative 1e-6 of the largest term, as for
    // springs. `pass_parity_in`'s 2e-5 of the largest force leaves 10× margin.
    let prep = prepare(&membrane_sheet(32)).unwrap();
    assert!(!prep.model.membranes.is_empty());
    assert!(prep.model.springs.iter().all(|s| s.stiffness == 0.0));
    pass_parity_in(prep, Pass::MembraneForces);
}

/// The membrane sheet with conditions that buckle: the 5 mm perturbation compresses many of
/// them past their Euler strain (about 1e-4 here), where the law's buckled branch carries
/// their force. The bound is `parity_membrane_forces`'s: the buckled tension carries the same
/// rounding of the strain as the linear one.
#[test]
fn parity_membrane_forces_buckling() {
    let mut scene = membrane_sheet(32);
    scene.fabric.buckling = true;
    let prep = prepare(&scene).unwrap();
    assert!(prep.params.membrane_onset > 0.0 && prep.params.buckled_fraction > 0.0);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let state = perturbed(&cpu.state().unwrap(), 7, 5e-3, 0.5);
    let buckled = common::buckled_conditions(&prep, &state.positions);
    let conditions = 2 * prep.model.membranes.len();
    assert!(
        buckled * 5 > conditions,
        "only {buckled} of {conditions} buckled"
    );
    pass_parity_in(prep, Pass::MembraneForces);
}

/// The membrane sheet stiffening in tension (its large-strain tangents 10 times its warp and
/// twice its weft, reached at 1/6: unequal, so that a warp/weft swap shows): the 5 mm
/// perturbation stretches many conditions within the growth and some beyond it. The bound is
/// `parity_membrane_forces`'s: the stiffened tension carries the strain's rounding times its
/// tangent, which is at most twice its secant, in a force that grows by the secant alike.
#[test]
fn parity_membrane_forces_stiffening() {
    let mut scene = membrane_sheet(32);
    let membrane = scene.fabric.membrane.as_mut().expect("a membrane");
    membrane.large_strain = Some([3000.0, 300.0]);
    let prep = prepare(&scene).unwrap();
    assert!(prep.params.stiffening[0] > 0.0 && prep.params.stiffening[2] > 0.0);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let state = perturbed(&cpu.state().unwrap(), 7, 5e-3, 0.5);
    let (within, beyond) = common::stiffened_conditions(&prep, &state.positions);
    let conditions = 2 * prep.model.membranes.len();
    assert!(
        within * 5 > conditions && beyond > 0,
        "{within} within, {beyond} beyond of {conditions}"
    );
    pass_parity_in(prep, Pass::MembraneForces);
}

#[test]
fn parity_strain_limit() {
    // The 5 mm perturbation stretches the flag's 4.3 cm edges by up to 23%: past the 10% limit.
    pass_parity(Pass::StrainLimit);
}

#[test]
fn parity_integrate() {
    pass_parity(Pass::Integrate);
}

/// The two ways of evaluating hinges give the same bits on the CPU when bending is the last
/// force before integrate: each hinge's force on a vertex is the same arithmetic whether
/// evaluated once or from each vertex, and each particle sums its hinges in the same CSR order.
/// (With wind or seams the once-per-hinge sum is added after theirs: rounding may then differ.)
#[test]
fn hinges_once_and_per_vertex_give_the_same_bits_on_the_cpu() {
    let mut scene = Scene::load(&fixture("scenes/hanging_cloth.toml")).unwrap();
    scene.solver.frames = 6;
    let prep = prepare(&scene).unwrap();
    let run = |how: HingeEvaluation| {
        let plan = prep.plan.with_hinges(how);
        let mut cpu = CpuSolver::new(&prep.model, prep.params, &plan);
        let mut sub = prep.clone();
        sub.plan = plan;
        simulate(&sub, &mut cpu, &mut RunStats::default(), |_, _| Ok(())).unwrap();
        cpu.state().unwrap()
    };
    let (once, per_vertex) = (run(HingeEvaluation::Once), run(HingeEvaluation::PerVertex));
    assert!(prep.hinges_in_use() > 0);
    assert!(
        once.positions != prep.model.packed_positions(),
        "nothing moved"
    );
    assert_eq!(once.positions, per_vertex.positions);
    assert_eq!(once.velocities, per_vertex.velocities);
}

/// Runs the hanging cloth for 2 simulated seconds on both backends and compares every frame.
fn trajectory_parity(integrator: u32) {
    let mut scene = Scene::load(&fixture("scenes/hanging_cloth.toml")).unwrap();
    // 16×16 keeps the explicit run (whose stable step is ζ-limited) short on lavapipe.
    if let drapekit::scene::ClothSource::Grid { columns, rows, .. } = &mut scene.cloth {
        *columns = 16;
        *rows = 16;
    }
    trajectory_parity_of(scene, integrator);
}

/// Runs `scene` for 2 simulated seconds with `integrator` on both backends and compares every
/// frame.
fn trajectory_parity_of(mut scene: Scene, integrator: u32) {
    let Some(ctx) = gpu() else { return };
    scene.solver.integrator = integrator;
    scene.solver.frames = 48; // 2 s at 24 fps
    let prep = prepare(&scene).unwrap();
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(
        ctx,
        &prep.model,
        prep.params,
        &prep.plan,
        prep.substeps as usize,
    )
    .unwrap();
    let mut cpu_frames = Vec::new();
    simulate(&prep, &mut cpu, &mut RunStats::default(), |_, s| {
        cpu_frames.push(s.clone());
        Ok(())
    })
    .unwrap();
    let mut gpu_frames = Vec::new();
    simulate(&prep, &mut gpu, &mut RunStats::default(), |_, s| {
        gpu_frames.push(s.clone());
        Ok(())
    })
    .unwrap();
    let name = format!(
        "{} sheet{}, integrator {integrator}",
        if prep.model.membranes.is_empty() {
            "spring"
        } else {
            "membrane"
        },
        if prep.params.buckled_fraction > 0.0 {
            " that buckles"
        } else {
            ""
        },
    );
    frame_by_frame(&name, &prep, &mut gpu, &cpu_frames);
    if !on_fallback() {
        // Whole runs part after a fold on a hardware GPU (frame_by_frame checked every frame);
        // the GPU's own run must still stay finite.
        let finite = |s: &ParticleState| s.positions.iter().all(|p| p.is_finite());
        assert!(
            gpu_frames.iter().all(finite),
            "{name}: the GPU's run is not finite"
        );
        return;
    }
    let mut worst = (0.0f32, 0usize);
    for (f, (g, c)) in gpu_frames.iter().zip(&cpu_frames).enumerate() {
        let d = max_abs_diff(&g.positions, &c.positions);
        if d > worst.0 {
            worst = (d, f);
        }
    }
    let steps = prep.frames as f32 * prep.substeps as f32;
    // Each substep may round differently on the two backends by ~1 ulp of a 1.5 m position
    // (2^-24·1.5 ≈ 9e-8 m). The scene is damped (ζ = 0.1 per spring, 0.2/s air) and hangs
    // towards one equilibrium, so differences are not amplified; if they simply added up, after
    // N substeps they would reach N·9e-8 m. Allow that linear bound.
    let bound = steps * 9e-8;
    eprintln!("integrator {integrator}: max deviation {:.3e} m at frame {} (bound {bound:.3e} m over {steps} substeps)", worst.0, worst.1);
    assert!(
        worst.0 <= bound,
        "deviation {} m at frame {} exceeds {bound} m",
        worst.0,
        worst.1
    );
}

/// Each frame of the CPU's run stepped again on the GPU from the CPU's state at the frame
/// before: every state of the trajectory checked on the GPU without the differences of the
/// frames before it, so that a fold that goes one way on the CPU and the other way on the GPU
/// (the hanging sheet wrinkles as it falls and swings, and the mirror image x → −x is as right
/// as the original) cannot set the two apart for the rest of the run.
///
/// A hardware GPU may round each substep differently from the CPU twin: WGSL lets it contract
/// a·b + c into an FMA and gives division and `inverseSqrt` 2.5 ULP, so a position may differ by
/// `ROUNDINGS` roundings a substep (a position update is a handful of such operations deep).
/// Within a frame such differences add up, or grow where the sheet is buckling. The yardstick
/// for both is the CPU itself: the same frame again from the same state with noise of up to one
/// rounding of every position coordinate (2^-24 of its size) added after each substep.
/// The GPU's frame must end within 2·ROUNDINGS times the noisy frame's distance from the CPU's
/// (2× for the randomness of one noisy run), or within ROUNDINGS roundings of a 1.5 m position
/// (2^-24 · 1.5 ≈ 9e-8 m) a substep added up over the frame, whichever is larger.
fn frame_by_frame(name: &str, prep: &Prepared, gpu: &mut GpuSolver, cpu_frames: &[ParticleState]) {
    const ROUNDINGS: f32 = 4.0;
    // A frame restarted from a state is the frame of the run only while nothing changes between
    // frames (gravity switched on, attachments let go).
    assert!(
        prep.gravity.1 == 0 && prep.attached.is_empty(),
        "{name}: phases"
    );
    let mut noisy = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut rng = common::Rng::new(11);
    let linear = prep.substeps as f32 * 9e-8;
    for frame in 1..cpu_frames.len() {
        let (start, cpu) = (&cpu_frames[frame - 1], &cpu_frames[frame].positions);
        let steps = substep_params(prep, frame as u32);
        gpu.set_state(start);
        gpu.advance(&steps).unwrap();
        let apart = max_abs_diff(&gpu.state().unwrap().positions, cpu);
        noisy.set_state(start);
        for step in &steps {
            noisy.advance(std::slice::from_ref(step)).unwrap();
            let mut s = noisy.state().unwrap();
            for p in s.positions.iter_mut().filter(|p| p.w != 0.0) {
                let noise = rng.vec3(f32::EPSILON / 2.0) * p.truncate().abs();
                *p += noise.extend(0.0);
            }
            noisy.set_state(&s);
        }
        let spread = max_abs_diff(&noisy.state().unwrap().positions, cpu);
        let bound = ROUNDINGS * (2.0 * spread).max(linear);
        eprintln!("{name} frame {frame}: GPU {apart:.2e} m from the CPU, noisy CPU {spread:.2e} m");
        assert!(
            apart <= bound,
            "{name} frame {frame}: one frame from the CPU's state ends {apart} m from the CPU, \
             bound {bound} m (noisy CPU {spread} m)"
        );
    }
}

#[test]
fn trajectory_parity_symplectic() {
    trajectory_parity(INTEGRATOR_SYMPLECTIC);
}

#[test]
fn trajectory_parity_explicit() {
    trajectory_parity(INTEGRATOR_EXPLICIT);
}

#[test]
fn trajectory_parity_membrane_symplectic() {
    // The 16×16 membrane sheet with its warp at 30°, damped as the spring sheet is (the
    // membrane's τ from the same damping ratio, and air): the same linear bound holds.
    let scene = membrane_sheet(16);
    trajectory_parity_of(scene, INTEGRATOR_SYMPLECTIC);
}

#[test]
fn trajectory_parity_buckling_symplectic() {
    // The hanging cloth with springs that buckle: the sag between its two pinned corners
    // compresses springs past their Euler onset, so the law's buckled branch steps the run on
    // both backends. The damped sheet still hangs towards one equilibrium: the same bound.
    let mut scene = Scene::load(&fixture("scenes/hanging_cloth.toml")).unwrap();
    if let drapekit::scene::ClothSource::Grid { columns, rows, .. } = &mut scene.cloth {
        (*columns, *rows) = (16, 16);
    }
    scene.fabric.buckling = true;
    scene.solver.frames = 48; // the frames trajectory_parity_of compares, for the count
    let prep = prepare(&scene).unwrap();
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut buckled = 0;
    simulate(&prep, &mut cpu, &mut RunStats::default(), |_, s| {
        buckled = buckled.max(common::buckled_springs(&prep, &s.positions));
        Ok(())
    })
    .unwrap();
    assert!(buckled > 10, "{buckled} springs buckled");
    trajectory_parity_of(scene, INTEGRATOR_SYMPLECTIC);
}

/// The monitor stage's per-workgroup partials from one perturbed state: the kinetic energy is a
/// tree sum of 64 terms ½m|v|² (each a few f32 operations: relative 1e-6 of the largest term
/// per level, 6 levels), the speeds and strains are single evaluations (strain: the |d| − L
/// cancellation, 2e-6 relative as for springs), and the worst particle and counts are exact
/// unless two strains tie within that rounding.
#[test]
fn parity_monitor() {
    let Some(ctx) = gpu() else { return };
    let prep = flag();
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    let mut state = perturbed(&cpu.state().unwrap(), 11, 5e-3, 0.5);
    // Two broken particles: the first non-finite one and the count must agree.
    state.positions[700].y = f32::NAN;
    state.velocities[300].x = f32::INFINITY;
    cpu.set_state(&state);
    gpu.set_state(&state);
    let c = cpu.health().unwrap();
    let g = gpu.health().unwrap();
    assert_eq!(c.non_finite, 2);
    assert_eq!(c.first_non_finite, Some(300));
    assert_eq!(
        (g.non_finite, g.first_non_finite),
        (c.non_finite, c.first_non_finite)
    );
    assert!(c.kinetic_energy > 0.0 && c.max_strain > 0.0);
    let de = (g.kinetic_energy - c.kinetic_energy).abs();
    assert!(
        de <= 1e-5 * c.kinetic_energy,
        "kinetic energy {} vs {}",
        g.kinetic_energy,
        c.kinetic_energy
    );
    assert!((g.max_speed - c.max_speed).abs() <= 1e-6 * c.max_speed);
    assert!((g.max_strain - c.max_strain).abs() <= 2e-6 * (1.0 + c.max_strain.abs()));
    assert_eq!(g.worst, c.worst, "worst particle");
    // Gravitational and elastic energies: tree sums like the kinetic one; the elastic terms
    // carry the stretch cancellation twice (squared), 4e-6 relative each.
    for (what, a, b) in [
        ("gravitational", g.gravity_energy, c.gravity_energy),
        ("elastic", g.elastic_energy, c.elastic_energy),
    ] {
        assert!(b != 0.0, "{what} energy is zero");
        assert!((a - b).abs() <= 1e-5 * b.abs(), "{what} energy {a} vs {b}");
    }
    // The CPU's energy is the f64 sum of the same ½m|v|² over finite free particles.
    let direct: f64 = (state.positions.iter().zip(&state.velocities))
        .filter(|(p, v)| p.w > 0.0 && p.is_finite() && v.is_finite())
        .map(|(p, v)| 0.5 * v.truncate().length_squared() as f64 / p.w as f64)
        .sum();
    assert!(
        (c.kinetic_energy - direct).abs() <= 1e-5 * direct,
        "{} vs {direct}",
        c.kinetic_energy
    );
}

/// `positions` reads the positions alone (what `bench peer` reads each frame, as Warp's
/// benchmark does): the same values as the whole state's, after a few substeps.
#[test]
fn positions_alone_equal_the_states() {
    let Some(ctx) = gpu() else { return };
    let prep = flag();
    let mut g = GpuSolver::new(
        ctx,
        &prep.model,
        prep.params,
        &prep.plan,
        prep.substeps as usize,
    )
    .unwrap();
    let start = g.positions().unwrap();
    g.advance(&substep_params(&prep, 1)).unwrap();
    let positions = g.positions().unwrap();
    let state = g.state().unwrap();
    assert_eq!(positions, state.positions);
    assert_ne!(positions, start, "the frame moved the flag");
}
