//! Implicit Euler's converged solve on the CPU: every accepted Newton correction lowers the
//! incremental potential (computed here in f64, independently of the solver's f32 energy
//! differences), and the multigrid solve's convergence per Newton step does not degrade with
//! resolution, where plain Vertex Block Descent's does.

mod common;

use common::{fixture, Rng};
use drapekit::bench::convergence::{run_cli, ConvergenceOptions, ConvergenceRow};
use drapekit::bench::fas::{FAS_COARSENING, FAS_COARSE_SWEEPS};
use drapekit::cpu::{
    hinge_psi, line_energy, line_search, line_slopes, CpuSolver, Elements, Implicit, VbdElements,
    LINE_ALPHAS, LINE_ROUNDING,
};
use drapekit::model::layout::{SimParams, SubstepParams};
use drapekit::plan::{newton_correction, Pass, SolveOp, SolveShape, LINEAR_ITERATIONS};
use drapekit::scene::Scene;
use drapekit::sim::{phase_params, prepare, simulate, substep_params, Prepared, RunStats};
use drapekit::solver::Solver;
use glam::{DVec3, Vec4};

fn d3(v: Vec4) -> DVec3 {
    v.truncate().as_dvec3()
}

/// The sign and size of the dihedral angle's sin(θ/2) of a hinge at world points, in f64 (as
/// `hinge_forces` computes it in f32).
fn sin_half(x: [DVec3; 4]) -> Option<f64> {
    let [x3, x4, x1, x2] = x;
    let e = x4 - x3;
    let n1 = (x1 - x3).cross(x1 - x4);
    let n2 = (x2 - x4).cross(x2 - x3);
    if e.length() < 1e-12 || n1.length_squared() < 1e-24 || n2.length_squared() < 1e-24 {
        return None;
    }
    let (a, b) = (n1.normalize(), n2.normalize());
    let s = (0.5 * (1.0 - a.dot(b).clamp(-1.0, 1.0))).max(0.0).sqrt();
    Some(if a.cross(b).dot(e) < 0.0 { -s } else { s })
}

/// A spring's energy at stretch `s`: ½k·s², or with buckling (`buckled_fraction` r > 0)
/// ½k·s² down to the onset o = `euler_onset`/L and ½k·o² − k·o·u + ½rk·u² (u = s + o) beyond.
fn spring_energy(p: &SimParams, k: f64, rest: f64, s: f64) -> f64 {
    let r = p.buckled_fraction as f64;
    let o = p.euler_onset as f64 / rest;
    if r > 0.0 && s < -o {
        let u = s + o;
        0.5 * k * o * o - k * o * u + 0.5 * r * k * u * u
    } else {
        0.5 * k * s * s
    }
}

/// G(D) in f64 with each term's |value| summed alongside (for the rounding bound), from the
/// model's elements: inertia, air damping, springs and their damping along the step's start
/// direction, hinges w₀·ψ(θ), seam pairs (zero rest gap here: the seams are sewn), contact
/// penalty on the step's planes and friction's lagged potential. Written out here, not
/// through the solver's code.
fn potential(s: &Implicit, d: &[Vec4]) -> (f64, f64) {
    let p = s.params;
    let h = p.dt as f64;
    let (mut g, mut size) = (0.0f64, 0.0f64);
    let mut add = |v: f64| {
        g += v;
        size += v.abs();
    };
    let n = p.num_particles as usize;
    for (i, &di) in d.iter().enumerate().take(n) {
        if s.prev[i].w == 0.0 {
            continue;
        }
        let m = 1.0 / s.prev[i].w as f64;
        let di = d3(di);
        add(0.5 * m / (h * h) * (di - d3(s.target[i])).length_squared());
        add(0.5 * p.air_damping as f64 * m / h * di.length_squared());
        let k_c = s.contact_stiffness(i) as f64;
        for b in 0..p.num_bodies as usize {
            let body = &p.bodies[b];
            let plane = s.plane(b, i);
            let normal = d3(plane);
            let depth = body.thickness as f64 - (plane.w as f64 + normal.dot(di));
            add(0.5 * k_c * depth.max(0.0).powi(2));
            let lambda = s.lambdas[i][b] as f64;
            if lambda > 0.0 {
                // The test's body does not move: the slip is the displacement in the plane.
                let u = di - di.dot(normal) * normal;
                let eps = (body.friction_slip_speed * p.dt) as f64;
                let len = u.length();
                let f0 = if len < eps {
                    len * len / (2.0 * eps)
                } else {
                    len - 0.5 * eps
                };
                add(body.friction as f64 * lambda * f0);
            }
        }
    }
    let el: &VbdElements = s.el;
    let (offsets, springs) = el.springs;
    for i in 0..n {
        for sp in &springs[offsets[i] as usize..offsets[i + 1] as usize] {
            let j = sp.other as usize;
            if j < i {
                continue;
            }
            let start = d3(s.prev[i]) - d3(s.prev[j]);
            let change = d3(d[i]) - d3(d[j]);
            let stretch = (start + change).length() - sp.rest_length as f64;
            add(spring_energy(
                p,
                sp.stiffness as f64,
                sp.rest_length as f64,
                stretch,
            ));
            let dn = start.normalize_or_zero().dot(change);
            add(0.5 * sp.damping as f64 / h * dn * dn);
        }
    }
    // The element lists hold each element once per vertex it acts on (at the vertex's ref):
    // each counts once, at its role-0 ref, as the solve's own energy change counts it.
    if let Some((_, refs, hinges)) = el.hinges {
        for (hinge, _) in hinges.iter().zip(refs).filter(|(_, &r)| r % 4 == 0) {
            let x = hinge.v.map(|v| d3(s.prev[v as usize]) + d3(d[v as usize]));
            if let Some(sh) = sin_half(x) {
                add(hinge.rest_weight as f64 * hinge_psi(sh as f32, hinge.rest_sin_half) as f64);
            }
        }
    }
    if let Some((_, refs, seams)) = el.seams {
        for (seam, _) in seams.iter().zip(refs).filter(|(_, &r)| r % 4 == 0) {
            let w = seam.weight as f64;
            let [a, b0, b1] = [seam.v[0], seam.v[1], seam.v[2]].map(|v| v as usize);
            let x = |k: usize| d3(s.prev[k]) + d3(d[k]);
            let gap = (1.0 - w) * x(b0) + w * x(b1) - x(a);
            let opening = (1.0 - w) * d3(d[b0]) + w * d3(d[b1]) - d3(d[a]);
            add(0.5 * seam.stiffness as f64 * gap.length_squared());
            add(0.5 * seam.damping as f64 / h * opening.length_squared());
        }
    }
    (g, size)
}

#[test]
fn an_accepted_newton_correction_never_raises_the_incremental_potential() {
    let scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    accepted_corrections_never_raise_the_potential(scene);
}

/// The same with springs that buckle: after 1 mm of noise many are compressed past their
/// Euler onset, so the line search's energy change takes the buckled branch.
#[test]
fn an_accepted_newton_correction_never_raises_the_potential_with_buckling() {
    let scene = common::scene_with_fabric("scenes/tshirt_drape_cotton.toml", common::BUCKLING);
    accepted_corrections_never_raise_the_potential(scene);
}

/// The solver run through `prep`'s frames (until it settles or ends), then set up for the
/// next frame's first substep: its parameters, the step's values, the inertial target and the
/// contact planes, as a substep begins.
fn next_substep(prep: &Prepared) -> (CpuSolver, RunStats, SimParams, SubstepParams) {
    let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = RunStats::default();
    simulate(prep, &mut solver, &mut stats, |_, _| Ok(())).unwrap();
    let frame = stats.frames_run;
    let params = phase_params(prep, frame, &stats);
    solver.set_params(&params);
    let step = substep_params(prep, frame + 1)[0];
    solver.run_pass(Pass::VbdInit, &step);
    solver.run_solve_ops(&[SolveOp::ContactPlanes], &step);
    (solver, stats, params, step)
}

/// The implicit terms at the solver's current substep.
fn terms<'a>(
    params: &'a SimParams,
    step: &'a SubstepParams,
    solver: &'a CpuSolver,
    el: &'a VbdElements<'a>,
) -> Implicit<'a> {
    let v = solver.vbd.as_ref().unwrap();
    Implicit {
        params,
        step,
        prev: &solver.pos,
        target: &v.y,
        el,
        planes: &v.planes,
        lambdas: &v.lambdas,
    }
}

/// The cotton T-shirt (`scene`) meshed at 4 cm, sewn and draped for 36 frames, then one
/// substep whose iterate is pushed 1 mm off at random: the Newton corrections have work to do.
fn accepted_corrections_never_raise_the_potential(mut scene: Scene) {
    if let drapekit::scene::ClothSource::Pattern { options, .. } = &mut scene.cloth {
        options.particle_distance = 0.04;
    }
    scene.solver.substeps = Some(4);
    scene.solver.iterations = Some(1);
    scene.solver.settle_speed = None;
    scene.solver.frames = 36;
    let prep = prepare(&scene).unwrap();
    assert!(
        prep.model.multigrid.is_some(),
        "the 4 cm shirt has coarse levels"
    );
    let (mut solver, stats, params, step) = next_substep(&prep);
    assert_eq!(stats.frames_run, 36, "the shirt runs its 36 frames");
    let mut rng = Rng::new(23);
    {
        let v = solver.vbd.as_mut().unwrap();
        for (x, p) in v.x.iter_mut().zip(&solver.pos) {
            if p.w != 0.0 {
                *x += rng.vec3(1e-3).extend(0.0);
            }
        }
    }
    if params.buckled_fraction > 0.0 {
        let v = solver.vbd.as_ref().unwrap();
        let at: Vec<Vec4> = solver.pos.iter().zip(&v.x).map(|(p, d)| *p + *d).collect();
        let buckled = common::buckled_springs(&prep, &at);
        let springs = prep.model.springs.len();
        assert!(
            buckled * 5 > springs,
            "only {buckled} of {springs} springs buckled"
        );
    }
    let shape = SolveShape::for_run(&prep.model, &params, &prep.plan);
    let elements = Elements::new(&prep.model);
    let el = elements.view();
    let mut accepted = 0;
    for k in 0..6 {
        let before = solver.vbd.as_ref().unwrap().x.clone();
        solver.run_solve_ops(&newton_correction(shape), &step);
        let v = solver.vbd.as_ref().unwrap();
        let alpha = *v.newton.as_ref().unwrap().alphas.last().unwrap();
        let s = terms(&params, &step, &solver, &el);
        let (g0, size0) = potential(&s, &before);
        let (g1, size1) = potential(&s, &v.x);
        // The line search summed the change in f32: each term's change is exact to a few
        // ulps of the terms it differences, so its error is within 1e-6 of their sizes (16
        // ulps of f32, 6e-8 each), which bounds how far above zero an accepted change can be
        // here, far from balance, where the change of G decides (the slopes' band near balance:
        // the last test below).
        let rounding = 1e-6 * (size0 + size1);
        if alpha > 0.0 {
            accepted += 1;
            assert!(
                g1 - g0 <= rounding,
                "step {k}: G rose by {} J (α = {alpha}, rounding {rounding} J)",
                g1 - g0
            );
        } else {
            assert_eq!(
                before, v.x,
                "a rejected correction leaves the iterate alone"
            );
        }
        // Sweeps between the corrections, as the schedule runs them.
        let sweeps = vec![SolveOp::Sweep { iteration: 0 }; 2];
        solver.run_solve_ops(&sweeps, &step);
    }
    assert!(
        accepted >= 3,
        "only {accepted} of 6 corrections were accepted"
    );
}

fn curve<'a>(rows: &'a [ConvergenceRow], refinement: u32, method: &str) -> Vec<&'a ConvergenceRow> {
    rows.iter()
        .filter(|r| r.refinement == refinement && r.method == method)
        .collect()
}

#[test]
fn newton_steps_and_multigrid_cycles_converge_alike_at_three_resolutions_where_sweeps_do_not() {
    // The cotton sheet hanging from two corners at 17², 33² and 65² particles, its first substep
    // (gravity loads the flat sheet): every method solves it from the same start.
    let out = std::env::temp_dir().join(format!("drapekit-converged-{}", std::process::id()));
    let rows = run_cli(&ConvergenceOptions {
        scene: fixture("scenes/hanging_sheet_cotton.toml"),
        out: out.clone(),
        frames: Some(0),
        refinements: vec![1, 2, 4],
        max_sweeps: 256,
        max_newton: 4,
        relax_frames: 0,
        linear_iterations: LINEAR_ITERATIONS,
        fas_coarsening: FAS_COARSENING,
        fas_sweeps: FAS_COARSE_SWEEPS,
    })
    .unwrap();
    for name in ["convergence.csv", "convergence.md", "convergence.svg"] {
        assert!(out.join(name).metadata().unwrap().len() > 0, "{name}");
    }
    // Each Newton step reports how far its linear solve got, |f − H·c|/|f|. A Newton step
    // cannot cut the force residual by more than the share its linear solve leaves, so the
    // thousandfold cut asserted below needs that share under 1e-3 at every resolution
    // (measured: 2e-7 to 3.2e-4, the largest at the finest sheet's first step). Sweeps have
    // no linear solve.
    let bound = 1e-3;
    for r in &rows {
        match (r.method, r.linear_residual) {
            ("vbd", None) => {}
            ("newton-multigrid", Some(l)) => assert!(
                l <= bound,
                "{}× finer, Newton step {}: linear residual {l} over {bound}",
                r.refinement,
                r.iterations
            ),
            ("newton-block-jacobi", Some(l)) => assert!(l.is_finite()),
            ("fas", None) => {}
            (method, l) => panic!("{method} row with linear residual {l:?}"),
        }
    }
    // The residual after one sweep is where both methods start from.
    let start = |r: u32| curve(&rows, r, "vbd")[0].residual_rms;
    // Newton steps to cut the RMS residual a thousandfold, at each resolution.
    let steps: Vec<u32> = [1, 2, 4]
        .iter()
        .map(|&r| {
            let target = 1e-3 * start(r);
            curve(&rows, r, "newton-multigrid")
                .iter()
                .find(|p| p.residual_rms <= target)
                .map_or(u32::MAX, |p| p.iterations)
        })
        .collect();
    let (lo, hi) = (*steps.iter().min().unwrap(), *steps.iter().max().unwrap());
    assert!(
        hi <= 4 && hi <= 2 * lo,
        "Newton steps to a 1000-fold cut: {steps:?}"
    );
    // Per cycle, the multigrid's own rate: each conjugate-gradient iteration of a Newton step
    // is preconditioned by one V-cycle, so the first step's linear residual after its
    // LINEAR_ITERATIONS cycles gives the digits each cycle gains. Only the first step's: its
    // right-hand side is the sheet's whole weight, while later steps start near f32's rounding
    // and stop at it (2e-7). Multigrid's rate must not depend on the mesh: within a factor 2
    // from 17² to 65² (measured: 0.59, 0.51 and 0.44 digits a cycle, a spread of 1.34). The
    // linear-residual bound above already keeps every rate between 0.375 (1e-3 after 8 cycles)
    // and about 0.84 (f32's floor), a spread of at most 2.24, so this factor adds little to
    // it; the rate that falls with the mesh is the sweeps', below.
    let rate = |digits: f64, cycles: f64| digits / cycles;
    let cycle_rates: Vec<f64> = [1, 2, 4]
        .iter()
        .map(|&r| {
            let first = curve(&rows, r, "newton-multigrid")[0];
            let linear = first.linear_residual.unwrap() as f64;
            rate(-linear.log10(), LINEAR_ITERATIONS as f64)
        })
        .collect();
    let spread = |v: &[f64]| {
        let (lo, hi) = (
            v.iter().cloned().fold(f64::MAX, f64::min),
            v.iter().cloned().fold(0.0, f64::max),
        );
        hi / lo
    };
    assert!(
        spread(&cycle_rates) <= 2.0,
        "multigrid digits per cycle at 17², 33², 65²: {cycle_rates:?}"
    );
    // A plain sweep's rate, the digits each sweep gains over the 256, falls with the mesh, by
    // far more than 2 (measured: 19 times from 17² to 65²).
    let sweep_rates: Vec<f64> = [1, 2, 4]
        .iter()
        .map(|&r| {
            let sweeps = curve(&rows, r, "vbd");
            let (first, last) = (sweeps[0], sweeps[sweeps.len() - 1]);
            let digits = (first.residual_rms as f64 / last.residual_rms as f64).log10();
            rate(digits, (last.iterations - first.iterations) as f64)
        })
        .collect();
    assert!(
        sweep_rates[2] < sweep_rates[0] / 2.0,
        "sweeps' digits per sweep at 17², 33², 65²: {sweep_rates:?}"
    );
    // 256 plain sweeps (6 to 40 times the Newton steps' cost) reach no 1000-fold cut, and
    // what they do reach shrinks with resolution: a sweep carries the load one ring further,
    // and the sheet is 16, 32 and 64 rings tall (measured: 7×, 1.6× and 1.1×).
    let vbd_cut = |r: u32| curve(&rows, r, "vbd").last().unwrap().residual_rms / start(r);
    assert!(
        vbd_cut(1) > 1e-3 && vbd_cut(4) > 4.0 * vbd_cut(1),
        "sweeps cut the residual to {} of its start at 17² and {} at 65²",
        vbd_cut(1),
        vbd_cut(4)
    );
    // Nonlinear multigrid (FAS) around the same sweeps, the alternative the Newton steps were
    // chosen over: a V-cycle through the sheet meshed 2, 4, … times coarser, each cycle's
    // correction through the same line search. On the hanging sheet every cycle is taken
    // (measured: α = 1 throughout) and helps: at 65² a cycle's 4 fine sweeps and coarse work
    // (each coarser level a quarter of the one above, 64 sweeps on the coarsest's 81
    // particles) cost about 10 sweeps, so 4 cycles cost less than 64 plain sweeps, and they
    // leave under half the residual those leave (measured 0.35 of it). But they cut it far
    // less than Newton's thousandfold in at most 4 steps: at 65² not even a hundredfold
    // (measured 0.34 of the start): the measurement behind shipping Newton's steps, not FAS.
    for r in [1, 2, 4] {
        let fas = curve(&rows, r, "fas");
        assert_eq!(fas.len(), 4, "{r}× finer: FAS cycles");
        for p in &fas {
            let alpha = p.step_length.unwrap();
            assert!(
                alpha > 0.0,
                "{r}× finer: FAS cycle {} refused",
                p.iterations
            );
        }
    }
    let fas_65 = curve(&rows, 4, "fas")[3].residual_rms;
    let vbd_64 = curve(&rows, 4, "vbd")
        .into_iter()
        .find(|p| p.iterations == 64)
        .unwrap()
        .residual_rms;
    assert!(
        fas_65 < 0.5 * vbd_64 && fas_65 > 1e-2 * start(4),
        "65²: 4 FAS cycles leave {fas_65}, 64 sweeps {vbd_64}, the start {}",
        start(4)
    );
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn newton_steps_go_on_where_the_change_of_g_is_lost_in_its_rounding() {
    // The cotton T-shirt at rest (2 cm, settled at frame 34), then one substep of twelve Newton
    // steps. After a few, a step lowers G by about 1e-11 J, while the f32 sum of its change
    // is only good to about 1e-9 J (the hinges' energies are differenced). With the hinges'
    // corners as world positions, a line search on that sum alone refused every step from the
    // fifth on and left the RMS force residual at 3.2e-3 of the weight; with G's slopes
    // deciding such changes it reached 2.7e-4. With the hinges in their own coordinates the
    // slopes reach 5.0e-4 at best over the twelve (measured), and the sum alone 9.8e-4 (its
    // steps raise the residual between the fourth and the seventh): this test now guards the
    // Newton steps' progress at rest, 1e-3 a factor 2 above it, and the near-balance test
    // below checks that the slopes take steps the sum alone would refuse.
    let out = std::env::temp_dir().join(format!("drapekit-rounding-{}", std::process::id()));
    let rows = run_cli(&ConvergenceOptions {
        scene: fixture("scenes/tshirt_drape_cotton.toml"),
        out: out.clone(),
        frames: None,
        refinements: vec![1],
        max_sweeps: 1,
        max_newton: 12,
        relax_frames: 0,
        linear_iterations: LINEAR_ITERATIONS,
        fas_coarsening: 0,
        fas_sweeps: FAS_COARSE_SWEEPS,
    })
    .unwrap();
    let newton = curve(&rows, 1, "newton-multigrid");
    assert_eq!(newton.len(), 12);
    let best = (newton.iter().map(|r| r.residual_rms)).fold(f32::MAX, f32::min);
    assert!(
        best < 1e-3,
        "the Newton steps stalled at an RMS force residual of {best} of the weight"
    );
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn near_balance_the_slopes_take_steps_that_do_not_raise_g_beyond_its_rounding() {
    // The cotton T-shirt run to rest, then twelve Newton corrections on the next substep, each
    // after the schedule's sweeps, as `bench convergence` runs them. Near balance G's f32
    // change falls within its rounding and the slopes decide: at least one step must be taken
    // so. Every taken step must not raise G, computed here in f64 independently, beyond the
    // rule's own bound (32ε of the scale the search summed; f64's own rounding of G, 1e-13 of
    // its terms' sizes, is far below it). That bound is loose here (8e-6 J against changes of
    // about 1e-9 J): a slope of the wrong sign shows in the residual test above, not here. The
    // CPU's lazy search must choose what the full search chooses from the same state and
    // correction.
    let scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    let prep = prepare(&scene).unwrap();
    let (mut solver, stats, params, step) = next_substep(&prep);
    assert!(stats.settled.is_some(), "the shirt settles");
    let shape = SolveShape::for_run(&prep.model, &params, &prep.plan);
    let elements = Elements::new(&prep.model);
    let el = elements.view();
    let sweeps = vec![SolveOp::Sweep { iteration: 0 }; shape.smoothing as usize];
    let mut by_slopes = 0;
    for k in 0..12 {
        solver.run_solve_ops(&sweeps, &step);
        let before = solver.vbd.as_ref().unwrap().x.clone();
        solver.run_solve_ops(&newton_correction(shape), &step);
        let v = solver.vbd.as_ref().unwrap();
        let newton = v.newton.as_ref().unwrap();
        let alpha = *newton.alphas.last().unwrap();
        let s = terms(&params, &step, &solver, &el);
        let groups = before.len().div_ceil(64);
        let (mut energy, mut slopes) = (vec![Vec4::ZERO; groups], vec![Vec4::ZERO; groups]);
        let c = &newton.correction;
        line_energy(&s, &before, c, &mut energy);
        line_slopes(&s, &before, c, &newton.force, &mut slopes);
        assert_eq!(
            alpha,
            line_search(&energy, &slopes),
            "step {k}: the full search"
        );
        let total = energy.iter().fold(Vec4::ZERO, |a, p| a + *p);
        let Some(taken) = LINE_ALPHAS.iter().position(|&a| a == alpha) else {
            assert_eq!(
                before, v.x,
                "step {k}: a refused correction leaves the iterate"
            );
            continue;
        };
        if total[taken] > 0.0 {
            by_slopes += 1;
        }
        let (g0, _) = potential(&s, &before);
        let (g1, _) = potential(&s, &v.x);
        let bound = (LINE_ROUNDING * total.w) as f64;
        assert!(
            g1 - g0 <= bound,
            "step {k}: G rose by {} J (α = {alpha}, bound {bound} J)",
            g1 - g0
        );
    }
    assert!(by_slopes >= 1, "no step was decided by the slopes");
}

#[test]
fn a_hinge_far_from_the_origin_bends_as_finely_as_its_own_size_allows() {
    // A hinge of cotton's rigidity (3.14e-5 N·m; the shirt's hinges carry four times that)
    // with 5 mm edges, bent by about 0.01 rad, at 1.3 m (a shoulder's height), where an f32
    // world coordinate rounds to 6e-8 m. Its far vertex x1 moves 5e-8 m
    // out of its triangle's plane: from world positions xₙ + D that move is lost (xₙ + D rounds
    // back to xₙ) and the force does not change, so Newton's steps could not balance the
    // bending force finer than such steps (the 5 mm shirt stalled at 2% of the weight). From
    // the hinge's own differences the change is resolved. The f64 force below is the hinge
    // force w₀(s − s₀)·u written out; each f32 force is good to a few roundings of sin(θ/2)
    // (its corners exact to ε of the 5 mm edges, its normals unit): w₀·|u|·8ε (ε = 2⁻²³),
    // doubled for a difference of two, a third of the 2.4e-8 N change.
    let base = DVec3::new(0.01, 1.3, 0.02);
    let l = 0.005;
    let h3 = 3f64.sqrt() / 2.0 * l;
    // [x3, x4, x1, x2]: the shared edge along x, x1 above it in -z, x2 in +z bent down 0.01.
    let local = [
        DVec3::ZERO,
        DVec3::new(l, 0.0, 0.0),
        DVec3::new(0.5 * l, 0.0, -h3),
        DVec3::new(0.5 * l, -0.01 * h3, h3),
    ];
    let prev: Vec<Vec4> = local
        .iter()
        .map(|p| (base + *p).as_vec3().extend(1.0))
        .collect();
    let normal = DVec3::Y;
    let delta = 5e-8;
    // An f32 in [1, 2) is a multiple of ε = 2⁻²³: half of that rounds away.
    assert!(
        delta < 0.5 * f64::from(f32::EPSILON),
        "under half an ulp at 1.3 m"
    );
    let params = SimParams {
        num_particles: 4,
        dt: 1.0 / 480.0,
        ..Default::default()
    };
    let stiffness = 3.14e-5;
    let exact = |x: [DVec3; 4]| {
        let [x3, x4, x1, _] = x;
        let n1 = (x1 - x3).cross(x1 - x4);
        let u = (x4 - x3).length() * n1 / n1.length_squared();
        sin_half(x).unwrap() * u
    };
    let corners = |moved: f64| {
        let mut x = prev.iter().map(|p| d3(*p)).collect::<Vec<_>>();
        x[2] += moved * normal;
        [x[0], x[1], x[2], x[3]]
    };
    let rest = prev.iter().map(|p| d3(*p)).collect::<Vec<_>>();
    let mut hinge = drapekit::model::layout::Hinge {
        v: [0, 1, 2, 3],
        stiffness,
        ..Default::default()
    };
    let (e, n1, n2) = (
        rest[1] - rest[0],
        (rest[2] - rest[0]).cross(rest[2] - rest[1]),
        (rest[3] - rest[1]).cross(rest[3] - rest[0]),
    );
    hinge.rest_weight =
        (stiffness as f64 * e.length_squared() / (n1.length() + n2.length())) as f32;
    let w0 = hinge.rest_weight as f64;
    let hinges = [hinge];
    let (hinge_offsets, refs) = ([0u32, 0, 0, 1, 1], [2u32]);
    let spring_offsets = [0u32; 5];
    let el = VbdElements {
        row_of: None,
        springs: (&spring_offsets, &[]),
        hinges: Some((&hinge_offsets, &refs, &hinges)),
        seams: None,
        membranes: None,
    };
    let force = |moved: f32| {
        let mut d = vec![Vec4::ZERO; 4];
        d[2] = (moved * normal.as_vec3()).extend(0.0);
        let step = Default::default();
        let lambdas = vec![Vec4::ZERO; 4];
        let s = Implicit {
            params: &params,
            step: &step,
            prev: &prev,
            // The inertial target at the iterate: the hinge's force alone.
            target: &d,
            el: &el,
            planes: &[],
            lambdas: &lambdas,
        };
        s.vertex_system(2, &d, None, &mut |_, _| {})
            .force
            .as_dvec3()
    };
    let change = force(delta as f32) - force(0.0);
    let exact_change = w0 * (exact(corners(delta)) - exact(corners(0.0)));
    let u = exact(corners(0.0)).length() / sin_half(corners(0.0)).unwrap();
    let bound = 2.0 * w0 * u * 8.0 * f64::from(f32::EPSILON);
    assert!(
        bound < exact_change.length() / 2.0,
        "the bound {bound} N resolves the change {} N",
        exact_change.length()
    );
    let error = (change - exact_change).length();
    assert!(
        error <= bound,
        "moving 5e-8 m changed the force by {change} N, the hinge by {exact_change} N \
         (off by {error} N, bound {bound} N)"
    );
}
