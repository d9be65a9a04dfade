//! Implicit Euler's solve on the GPU: its kernels validate and bind what they declare, their
//! shared structs match the Rust mirrors, and on lavapipe every stage matches its CPU twin
//! from identical inputs, and a small sewn garment's trajectory matches the CPU's (with edge
//! springs, and as an orthotropic membrane; substep by substep, and left to run).

mod common;

use drapekit::gpu::implicit::layout::{OpParams, SolveControl, SolveScalars};
use drapekit::gpu::implicit::SolveKernel;
use drapekit::gpu::kernels::{validate_wgsl, VbdEnergies};
use std::mem::{offset_of, size_of};

/// The energies' section combinations the solve kernels compose (contact is never a section
/// of theirs).
fn section_variants() -> impl Iterator<Item = VbdEnergies> {
    VbdEnergies::ALL.into_iter().filter(|e| !e.body)
}

#[test]
fn naga_validates_every_solve_kernel() {
    for kernel in SolveKernel::ALL {
        for energies in section_variants() {
            let composed = kernel.compose(energies);
            let label = format!("{} ({energies:?})", kernel.file());
            if let Err(report) = composed.validate(&label) {
                panic!("{report}");
            }
        }
    }
}

#[test]
fn solve_kernel_errors_name_the_file_and_line() {
    // A composed module's error points into the file the line came from.
    let mut composed = SolveKernel::PcgStart.compose(VbdEnergies::ALL[0]);
    let before = composed.source.lines().count();
    composed.push("broken", "fn oops() { let x: f32 = 1u; }\n".into());
    let report = composed.validate("broken kernel").unwrap_err();
    assert!(report.contains("kernels/broken.wgsl:1:"), "{report}");
    assert!(!report.contains(&format!(":{}:", before + 1)), "{report}");
}

#[test]
fn solve_kernels_bind_what_they_declare() {
    // The bind group each kernel gets (its `binds`) has exactly the bindings its composed module
    // declares, each storage buffer writable exactly where the module may store to it.
    for kernel in SolveKernel::ALL {
        for energies in section_variants() {
            let module = kernel.compose(energies).validate(kernel.file()).unwrap();
            let mut declared: Vec<(u32, Option<bool>)> = module
                .global_variables
                .iter()
                .filter_map(|(_, var)| {
                    let binding = var.binding.as_ref()?;
                    assert_eq!(binding.group, 0, "{}", kernel.file());
                    let writable = match var.space {
                        naga::AddressSpace::Storage { access } => {
                            Some(access.contains(naga::StorageAccess::STORE))
                        }
                        _ => None,
                    };
                    Some((binding.binding, writable))
                })
                .collect();
            declared.sort();
            let binds: Vec<(u32, Option<bool>)> = kernel
                .binds(energies)
                .iter()
                .map(|&(r, w)| (r.binding(), r.is_storage().then_some(w)))
                .collect();
            assert_eq!(declared, binds, "{} ({energies:?})", kernel.file());
        }
    }
}

fn wgsl_struct(name: &str) -> (u32, Vec<(String, u32)>) {
    // solve.wgsl as a kernel composes it (its control binding resolved).
    let source = SolveKernel::PcgStart.compose(VbdEnergies::ALL[0]).source;
    let module = validate_wgsl("solve.wgsl", &source).expect("solve.wgsl validates");
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                let fields = (members.iter())
                    .map(|m| (m.name.clone().unwrap(), m.offset))
                    .collect();
                return (*span, fields);
            }
        }
    }
    panic!("struct {name} not found in solve.wgsl");
}

fn check_layout(name: &str, size: usize, offsets: &[(&str, usize)]) {
    let (span, fields) = wgsl_struct(name);
    assert_eq!(span as usize, size, "{name}: size");
    let got: Vec<(&str, usize)> = fields
        .iter()
        .map(|(n, o)| (n.as_str(), *o as usize))
        .collect();
    assert_eq!(got, offsets, "{name}: fields");
}

#[test]
fn solve_structs_match_their_rust_mirrors() {
    check_layout(
        "OpParams",
        size_of::<OpParams>(),
        &[
            ("level", offset_of!(OpParams, level)),
            ("first", offset_of!(OpParams, first)),
            ("count", offset_of!(OpParams, count)),
            ("slot", offset_of!(OpParams, slot)),
            ("flag", offset_of!(OpParams, flag)),
            ("_pad0", offset_of!(OpParams, _pad0)),
            ("_pad1", offset_of!(OpParams, _pad1)),
            ("_pad2", offset_of!(OpParams, _pad2)),
        ],
    );
    check_layout(
        "SolveControl",
        size_of::<SolveControl>(),
        &[
            ("done", offset_of!(SolveControl, done)),
            ("_pad0", offset_of!(SolveControl, _pad0)),
            ("residual_max", offset_of!(SolveControl, residual_max)),
            ("residual_rms", offset_of!(SolveControl, residual_rms)),
        ],
    );
    check_layout(
        "SolveScalars",
        size_of::<SolveScalars>(),
        &[
            ("rz", offset_of!(SolveScalars, rz)),
            ("alpha", offset_of!(SolveScalars, alpha)),
            ("line_alpha", offset_of!(SolveScalars, line_alpha)),
            ("newton_steps", offset_of!(SolveScalars, newton_steps)),
            ("_pad0", offset_of!(SolveScalars, _pad0)),
        ],
    );
}

// ---------------------------------------------------------------------------------------------
// Trajectories on lavapipe.

use common::{fixture, gpu, max_abs_diff};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::GpuSolver;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, substep_params, Prepared};
use drapekit::solver::Solver;

/// The sewn skirt on the mannequin (1,264 particles, three coarse levels) at 3 substeps a frame,
/// gravity on from the start: seams closing, hinges, contact and friction against the body, all
/// in the solve.
fn skirt(mut scene: Scene) -> Prepared {
    scene.solver.substeps = Some(3);
    scene.gravity_start = 0.0;
    prepare(&scene).unwrap()
}

#[test]
fn trajectory_parity_sewn_skirt() {
    let prep = skirt(Scene::load(&fixture("scenes/skirt_rotating_implicit.toml")).unwrap());
    assert!(prep.model.multigrid.is_some() && !prep.model.seams.is_empty());
    trajectory_within_rounding_spread(&prep);
}

#[test]
fn free_running_trajectory_parity_sewn_skirt() {
    let prep = skirt(Scene::load(&fixture("scenes/skirt_rotating_implicit.toml")).unwrap());
    free_trajectory_within_rounding_spread(&prep);
}

#[test]
fn trajectory_parity_membrane_skirt() {
    // The same skirt as a denim membrane with its warp at 30° on both panels: the membrane's
    // terms in every stage of the solve, and no spring.
    let scene = common::scene_with_fabric(
        "scenes/skirt_rotating_implicit.toml",
        common::MEMBRANE_GRAIN_30,
    );
    let prep = skirt(scene);
    assert!(!prep.model.membranes.is_empty() && prep.model.multigrid.is_some());
    trajectory_within_rounding_spread(&prep);
}

/// Steps 3 frames of `prep` on the CPU and, substep by substep from the CPU's state, on the GPU
/// and on the CPU with rounding-sized noise, and compares the GPU's substep with the noisy one.
fn trajectory_within_rounding_spread(prep: &Prepared) {
    // The skirt being sewn is not at rest and its solve not converged, so a substep amplifies
    // rounding-sized differences, most of all the first from the flat panels at rest (its
    // linear system is at its worst conditioning: on lavapipe the two backends' assembled
    // systems agree to 1e-7 and their forces exactly, but the conjugate-gradient iterates part
    // by 1e-3 of the correction before they meet again). Over several substeps the
    // amplification compounds chaotically, so each substep is compared from a common state:
    // the CPU's. The GPU's substep differs from the CPU's by a few roundings in each stage,
    // which the substep amplifies; the CPU's own substep from that state with noise of one
    // rounding of every position (2^-24 of the largest coordinate, ~6e-8 m) shows how much. The
    // GPU may differ by a few times the noisy separation: 8×, which leaves room for the
    // randomness of one noise draw (measured on lavapipe: at most 1.1× on both skirts).
    let Some(ctx) = gpu() else { return };
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut noisy = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    let noise = one_rounding(&cpu.state().unwrap());
    let mut rng = common::Rng::new(5);
    for frame in 1..=3 {
        for (k, step) in substep_params(prep, frame).iter().enumerate() {
            let from = cpu.state().unwrap();
            let mut jittered = from.clone();
            for p in jittered.positions.iter_mut().filter(|p| p.w != 0.0) {
                *p += rng.vec3(noise).extend(0.0);
            }
            gpu.set_state(&from);
            noisy.set_state(&jittered);
            for solver in [&mut cpu as &mut dyn Solver, &mut gpu, &mut noisy] {
                solver.advance(std::slice::from_ref(step)).unwrap();
            }
            let (c, g, n) = (
                cpu.state().unwrap(),
                gpu.state().unwrap(),
                noisy.state().unwrap(),
            );
            let apart = max_abs_diff(&c.positions, &g.positions);
            let spread = max_abs_diff(&c.positions, &n.positions);
            let moved = max_abs_diff(&c.positions, &from.positions);
            eprintln!(
                "frame {frame} substep {k}: GPU {apart:.2e} m from the CPU, noisy CPU {spread:.2e} m \
                 (moved {moved:.2e} m)"
            );
            assert!(
                apart <= 8.0 * spread,
                "frame {frame} substep {k}: {apart} m apart, spread {spread} m"
            );
            let (rc, rg) = (
                cpu.residual().unwrap().unwrap(),
                gpu.residual().unwrap().unwrap(),
            );
            assert_eq!(rc.iterations, rg.iterations, "sweeps run");
        }
    }
}

/// One rounding of the largest coordinate of `state`'s positions (2^-24 of it): the noise
/// the trajectory tests start a CPU run from to show how far rounding alone parts two runs.
fn one_rounding(state: &drapekit::solver::ParticleState) -> f32 {
    let x_max = (state.positions.iter())
        .map(|p| p.truncate().abs().max_element())
        .fold(0.0, f32::max);
    x_max * f32::EPSILON / 2.0
}

/// Runs 6 frames of `prep` three ways, each on its own from the start: on the CPU, on the GPU,
/// and on the CPU from a start one rounding away, and compares the GPU's trajectory with the
/// perturbed one's distance from the CPU's at every substep.
fn free_trajectory_within_rounding_spread(prep: &Prepared) {
    // Left to run, the backends' roundings compound: a Newton step's line search or a contact
    // that falls the other way parts two trajectories by millimetres at once (one rounding of
    // every position, ~6e-8 m, already parts the CPU from itself by 2.7 mm in the second
    // substep). Those are the answers the equations allow; the GPU must give one of them, not
    // a trajectory much farther from the CPU's than one rounding of the start leads to.
    // Measured on lavapipe: the GPU within 1e-6 m of the CPU for 14 substeps, then parted by a
    // branch, at most 0.48 times the perturbed CPU's distance. Bound: 2×. Once a branch has
    // parted them, the GPU's trajectory and the perturbed one are two draws of the same
    // spread, and one draw may land nearer the CPU's than another. So only the first substep's
    // bound is tight (2.6e-5 m, where the GPU is 6e-8 m off); after it the bound is millimetres
    // and catches only a GPU path that goes its own way.
    let Some(ctx) = gpu() else { return };
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut noisy = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    let mut start = cpu.state().unwrap();
    let noise = one_rounding(&start);
    let mut rng = common::Rng::new(5);
    for p in start.positions.iter_mut().filter(|p| p.w != 0.0) {
        *p += rng.vec3(noise).extend(0.0);
    }
    noisy.set_state(&start);
    for frame in 1..=6 {
        for (k, step) in substep_params(prep, frame).iter().enumerate() {
            for solver in [&mut cpu as &mut dyn Solver, &mut gpu, &mut noisy] {
                solver.advance(std::slice::from_ref(step)).unwrap();
            }
            let c = cpu.state().unwrap().positions;
            let apart = max_abs_diff(&c, &gpu.state().unwrap().positions);
            let spread = max_abs_diff(&c, &noisy.state().unwrap().positions);
            eprintln!("frame {frame} substep {k}: GPU {apart:.2e} m, noisy CPU {spread:.2e} m");
            assert!(
                apart <= 2.0 * spread,
                "frame {frame} substep {k}: {apart} m apart, spread {spread} m"
            );
        }
    }
}

#[test]
fn every_substep_solves_until_its_own_tolerance() {
    // The tolerance check's `done` flag ends one substep's solve on the device; the next
    // substep starts solving again (vbd_init clears it). The hanging cloth falling from its
    // pins, at most 20 Newton steps a substep, stopping at an RMS force residual of 5% of the
    // weight: each substep stops early on both backends, within a Newton step of each other
    // (a residual at the tolerance may fall either side of it by rounding). Each substep
    // starts the GPU from the CPU's state, so the two solve the same equations wherever the
    // trajectories would part (on hardware GPUs, which round differently, they do).
    let Some(ctx) = gpu() else { return };
    let mut scene = Scene::load(&fixture("scenes/hanging_cloth.toml")).unwrap();
    scene.solver.integrator = drapekit::model::layout::INTEGRATOR_IMPLICIT;
    scene.solver.substeps = Some(2);
    scene.solver.iterations = Some(20);
    scene.solver.tolerance = Some(0.05);
    let prep = prepare(&scene).unwrap();
    assert!(prep.model.multigrid.is_some());
    let smoothing = scene.solver.smoothing_sweeps as u64;
    let most = smoothing * (20 + 1);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 2).unwrap();
    for frame in 1..=2 {
        for step in substep_params(&prep, frame) {
            gpu.set_state(&cpu.state().unwrap());
            cpu.advance(&[step]).unwrap();
            gpu.advance(&[step]).unwrap();
            let (c, g) = (
                cpu.residual().unwrap().unwrap(),
                gpu.residual().unwrap().unwrap(),
            );
            eprintln!(
                "frame {frame}.{}: CPU {} sweeps, {:?}; GPU {} sweeps, {:?}",
                step.substep, c.iterations, c.force_residual, g.iterations, g.force_residual
            );
            // Every substep sweeps at least `smoothing` times before its first check.
            assert!(g.iterations >= smoothing && g.iterations < most, "{g:?}");
            assert!(
                g.iterations.abs_diff(c.iterations) <= smoothing,
                "{g:?} vs {c:?}"
            );
            assert!(g.force_residual.1 <= 0.05, "{g:?}");
        }
    }
}
