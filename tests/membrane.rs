//! The orthotropic membrane against its own definition and against mechanics: a sheet stretched
//! along the warp, the weft and at 45° has the uniaxial stiffness the fabric was given (the
//! classical off-axis formula at 45°); the force is minus the energy's gradient and the Hessian
//! blocks its derivative; a rigid rotation costs nothing; and a bias-cut strip hanging under its
//! own weight stretches as much more than a straight-grain one as the shear stiffness says.

mod common;

use drapekit::cpu::membrane::{image, membrane_force, MembraneStep};
use drapekit::mesh::{GridPlane, TriMesh};
use drapekit::model::layout::{Membrane, SimParams};
use drapekit::model::membrane::world_grain;
use drapekit::model::ClothModel;
use drapekit::scene::{Fabric, Orthotropic, Scene};
use drapekit::sim::{prepare, simulate, RunStats};
use glam::{Mat2, Quat, Vec2, Vec3, Vec4};

/// The measured cotton behind the `cotton` preset: warp, weft and shear in N/m.
const COTTON: Orthotropic = Orthotropic {
    warp: 4033.0,
    weft: 4069.9,
    shear: 52.0,
    bending: None,
    large_strain: None,
};

/// A 0.5 m square sheet of 9 × 9 particles in the xy plane, its warp `grain` radians from x, no
/// damping (τ = 0: the energy is the elastic energy alone).
fn sheet(fabric: Orthotropic, grain: f32) -> ClothModel {
    let mesh = TriMesh::grid(0.5, 0.5, 9, 9, Vec3::ZERO, GridPlane::Xy);
    let fabric = Fabric {
        density: 0.2,
        stretch_stiffness: fabric.warp,
        bending_stiffness: None,
        damping_ratio: 0.0,
        preset: None,
        membrane: Some(fabric),
        buckling: false,
    };
    let mut model = ClothModel::from_mesh(&mesh, &fabric, &[]);
    model.set_grain(
        &world_grain(mesh.triangles.len(), grain, Vec3::Z),
        &fabric,
        &[],
    );
    model
}

/// The membrane's energy when the sheet at rest `x` is displaced by `u` (the conditions'
/// change from rest, as the line search computes it).
fn energy(model: &ClothModel, x: &[Vec4], u: &[Vec4]) -> f32 {
    energy_with(&SimParams::default(), model, x, u)
}

/// `energy` under the compression law of `p`.
fn energy_with(p: &SimParams, model: &ClothModel, x: &[Vec4], u: &[Vec4]) -> f32 {
    let zero = vec![Vec4::ZERO; x.len()];
    model
        .membranes
        .iter()
        .map(|m| {
            let step = MembraneStep::at(m, x, &zero);
            let dw = [image(m, &step.a, u), image(m, &step.b, u)];
            step.energy_change(p, m, dw, 1.0)
        })
        .sum()
}

/// The displacement of the homogeneous in-plane strain (εx, εy, γ) (engineering shear) about
/// the sheet's centre.
fn strained(model: &ClothModel, s: [f32; 3]) -> Vec<Vec4> {
    let e = Mat2::from_cols(Vec2::new(s[0], 0.5 * s[2]), Vec2::new(0.5 * s[2], s[1]));
    model
        .positions
        .iter()
        .map(|p| (e * p.truncate()).extend(0.0).extend(0.0))
        .collect()
}

/// The sheet's uniaxial stiffness along x with its lateral strain and shear free: the Schur
/// complement of the 3×3 stiffness (by central second differences of the energy, which are
/// exact for a quadratic and cancel the odd terms) over its area.
fn uniaxial_along_x(model: &ClothModel) -> f32 {
    let x = model.packed_positions();
    let delta = 1e-3;
    let e = |s: [f32; 3]| energy(model, &x, &strained(model, s)) as f64;
    let unit = |k: usize| {
        let mut s = [0.0f32; 3];
        s[k] = delta;
        s
    };
    let mut k = [[0.0f64; 3]; 3];
    for (a, row) in k.iter_mut().enumerate() {
        for (b, entry) in row.iter_mut().enumerate() {
            let (sa, sb) = (unit(a), unit(b));
            let plus: [f32; 3] = std::array::from_fn(|c| sa[c] + sb[c]);
            let minus: [f32; 3] = std::array::from_fn(|c| sa[c] - sb[c]);
            let neg = |s: [f32; 3]| s.map(|v| -v);
            // ∂²E/∂a∂b = (E(a+b) − E(a−b) − E(−a+b) + E(−a−b)) / (4δ²).
            *entry = (e(plus) - e(minus) - e(neg(minus)) + e(neg(plus)))
                / (4.0 * (delta as f64).powi(2));
        }
    }
    // Minimise over (εy, γ): k_xx − k_xr·k_rr⁻¹·k_rx.
    let det = k[1][1] * k[2][2] - k[1][2] * k[2][1];
    let inv = [
        [k[2][2] / det, -k[1][2] / det],
        [-k[2][1] / det, k[1][1] / det],
    ];
    let r = [k[0][1], k[0][2]];
    let schur = k[0][0]
        - (r[0] * (inv[0][0] * r[0] + inv[0][1] * r[1])
            + r[1] * (inv[1][0] * r[0] + inv[1][1] * r[1]));
    let area = 0.25;
    (schur / area) as f32
}

#[test]
fn stretched_sheet_has_the_stiffness_it_was_given_along_warp_weft_and_bias() {
    for degrees in [0.0f32, 90.0, 45.0, 30.0] {
        let grain = degrees.to_radians();
        let model = sheet(COTTON, grain);
        let k = uniaxial_along_x(&model);
        // Pulling along x is pulling at −grain from the warp; 1/k(θ) is even in θ.
        let expected = COTTON.uniaxial(grain);
        // The energy is exact per triangle for a homogeneous strain; what is left is the
        // conditions' higher-order terms at δ = 1e-3, cancelled to O(δ²) by the central
        // differences, and f32 rounding of energies ~1e-4 J summed over 128 triangles (1e-6
        // relative), amplified by the Schur complement at most by k_warp/k_shear ≈ 80: 1e-3.
        let err = (k - expected).abs() / expected;
        assert!(
            err < 1e-3,
            "{degrees}°: {k} N/m, expected {expected} N/m ({err:e})"
        );
    }
    // The bias is 20 times softer than the warp: the shear stiffness, not the stretch, sets it.
    assert!(COTTON.uniaxial(std::f32::consts::FRAC_PI_4) < COTTON.warp / 19.0);
}

/// A sheet with its vertices moved randomly by up to `amount` m, warp at 30°.
fn deformed(amount: f32, seed: u32) -> (ClothModel, Vec<Vec4>) {
    let model = sheet(COTTON, 30f32.to_radians());
    let mut state = seed;
    let mut rand = || {
        state = state.wrapping_mul(1664525).wrapping_add(1013904223);
        (state >> 8) as f32 / (1u32 << 24) as f32 - 0.5
    };
    let x = model
        .packed_positions()
        .iter()
        .map(|p| *p + amount * Vec4::new(rand(), rand(), rand(), 0.0))
        .collect();
    (model, x)
}

#[test]
fn force_is_minus_the_energy_gradient() {
    force_is_minus_the_energy_gradient_with(&SimParams::default());
}

/// Conditions that buckle at 0.08 N·m of compression (1% on the cotton sheet's triangles),
/// carrying 3% of their stiffness beyond.
fn buckling() -> SimParams {
    SimParams {
        membrane_onset: 0.08,
        buckled_fraction: 0.03,
        ..Default::default()
    }
}

/// Conditions that stiffen, g = 20 per unit strain up to e = 0.05: a tangent twice k at 5%.
fn stiffening() -> SimParams {
    SimParams {
        stiffening: [20.0, 20.0, 0.05, 0.0],
        ..Default::default()
    }
}

/// The vertices whose force `force_is_minus_the_energy_gradient_with` checks, and its
/// central-difference step (m).
const GRADIENT_VERTICES: [usize; 4] = [0, 10, 40, 80];
const GRADIENT_STEP: f32 = 1e-5;

/// The same with conditions that buckle at 1% compression (K = k·A ≈ 4000 N/m × 2e-3 m² =
/// 8 N·m, onset 0.08 N·m / K): the sheet's 4 mm noise over 6 cm edges compresses some of the
/// checked vertices' conditions past it. The energy is only C¹ there: a central difference
/// across the onset errs by up to (1 − r)·K·c²·h/4 (about 5e-3 N), so the check asserts that
/// none of their conditions lies within the strain 2·|c|·h that its ±h moves reach.
#[test]
fn force_is_minus_the_energy_gradient_with_buckling() {
    let p = buckling();
    let (model, x) = deformed(4e-3, 7);
    let zero = vec![Vec4::ZERO; x.len()];
    let csr = model.membrane_csr();
    let mut buckled = 0;
    for i in GRADIENT_VERTICES {
        for &r in &csr.items[csr.offsets[i] as usize..csr.offsets[i + 1] as usize] {
            let m = &model.membranes[(r / 4) as usize];
            let step = MembraneStep::at(m, &x, &zero);
            for c in 0..2 {
                let (s, onset) = (step.stretch(c), p.membrane_onset / m.stiffness[c]);
                let reach = 2.0 * step.coefficient(c, (r % 4) as usize).abs() * GRADIENT_STEP;
                assert!(
                    (s + onset).abs() > reach,
                    "vertex {i}: strain {s} at the onset"
                );
                buckled += usize::from(s < -onset);
            }
        }
    }
    assert!(buckled >= 2, "{buckled} of the checked conditions buckled");
    force_is_minus_the_energy_gradient_with(&p);
}

/// The same for a membrane that stiffens steeply (g = 200 per unit strain up to e = 0.02):
/// the sheet's 4 mm noise over 6 cm edges stretches some checked conditions within the growth
/// and some beyond it. The energy is C² within each piece and C¹ in its tangent at e, so the
/// central differences' error stays the third derivative's, g·K·c³·h² (2e-5 N at most).
#[test]
fn force_is_minus_the_energy_gradient_with_stiffening() {
    let p = SimParams {
        stiffening: [200.0, 200.0, 0.02, 0.0],
        ..Default::default()
    };
    let (model, x) = deformed(4e-3, 7);
    let zero = vec![Vec4::ZERO; x.len()];
    let csr = model.membrane_csr();
    let (mut within, mut beyond) = (0, 0);
    for i in GRADIENT_VERTICES {
        for &r in &csr.items[csr.offsets[i] as usize..csr.offsets[i + 1] as usize] {
            let step = MembraneStep::at(&model.membranes[(r / 4) as usize], &x, &zero);
            for c in 0..2 {
                let s = step.stretch(c);
                within += usize::from(s > 0.0 && s <= 0.02);
                beyond += usize::from(s > 0.02);
            }
        }
    }
    assert!(
        within >= 2 && beyond >= 2,
        "{within} within, {beyond} beyond"
    );
    force_is_minus_the_energy_gradient_with(&p);
}

/// The jersey preset's weft, pulled uniaxially (no lateral strain: the model has no Poisson
/// coupling) with `tension = "stiffening"`: the tension the sheet carries at 1/6 is the one
/// Wang et al. 2011's fitted model gives there, (1 + e)·k_eff·(e + e²/2) with the lateral-free
/// k_eff = 696.1 N/m of its 90° large-strain sample (146.6 N/m, 20 times the linear
/// membrane's 7.15), and beyond it the tangent stays at the preset's 1,717 N/m.
#[test]
fn a_stiffening_jersey_carries_its_measured_tension() {
    let toml = "[cloth.grid]\nwidth_m = 0.2\nheight_m = 0.2\ncolumns = 7\nrows = 7\n\
         center_m = [0.0, 1.0, 0.0]\n\n[fabric]\npreset = \"jersey\"\nmodel = \"membrane\"\n\
         tension = \"stiffening\"\n\n[solver]\nfps = 24\nframes = 1\n";
    let scene = Scene::parse(toml, std::path::Path::new("jersey.toml")).expect("parses");
    let jersey = scene.fabric.membrane.unwrap();
    let model = sheet(jersey, 0.0);
    let p = SimParams {
        stiffening: scene.fabric.stiffening(),
        ..Default::default()
    };
    let x = model.packed_positions();
    // The energy per unit area of a uniform weft (y) strain s, and its tension by central
    // differences at ±1e-3·s.
    let area = 0.25;
    let energy = |s: f32| energy_with(&p, &model, &x, &strained(&model, [0.0, s, 0.0])) / area;
    let tension = |s: f32| {
        let h = 1e-3 * s;
        (energy(s + h) - energy(s - h)) / (2.0 * h)
    };
    let e = 1.0 / 6.0f32;
    let w11 = (1.0 + e) * 696.09 * (e + 0.5 * e * e);
    // Central differences of f32 energies (~10 J/m², rounding 1e-6 relative over 2e-3 of the
    // strain: 1e-3 relative of the tension) and the preset's four digits (1e-4): 2e-3.
    let at_e = tension(e);
    assert!((at_e / w11 - 1.0).abs() < 2e-3, "{at_e} N/m vs W11's {w11}");
    assert!(at_e > 19.0 * 42.92 * e, "{at_e}: not stiffened");
    // Beyond e the tension grows at the large-strain tangent: (T(0.25) − T(0.2))/0.05.
    let tangent = (tension(0.25) - tension(0.2)) / 0.05;
    assert!((tangent / 1716.6 - 1.0).abs() < 1e-2, "{tangent} N/m");
}

fn force_is_minus_the_energy_gradient_with(p: &SimParams) {
    let (model, x) = deformed(4e-3, 7);
    let vel = vec![Vec4::ZERO; x.len()];
    let csr = model.membrane_csr();
    let zero = vec![Vec4::ZERO; x.len()];
    let h = GRADIENT_STEP;
    for i in GRADIENT_VERTICES {
        let mut f = Vec3::ZERO;
        for &r in &csr.items[csr.offsets[i] as usize..csr.offsets[i + 1] as usize] {
            f += membrane_force(
                p,
                &model.membranes[(r / 4) as usize],
                (r % 4) as usize,
                &x,
                &vel,
            );
        }
        let mut grad = Vec3::ZERO;
        for axis in 0..3 {
            let mut u = zero.clone();
            u[i][axis] = h;
            let plus = energy_with(p, &model, &x, &u);
            u[i][axis] = -h;
            let minus = energy_with(p, &model, &x, &u);
            grad[axis] = (plus - minus) / (2.0 * h);
        }
        // Central differences err by h²·|∂³E| (a 6 cm element's third derivative, k·A/L³ ≈
        // 4000·0.002/2e-4 N/m² ≈ 4e4: 4e-6 N) plus the energies' f32 rounding over 2h (~1e-7
        // relative of ~1e-3 J per 2e-5 m: 5e-6 N); the forces are ~1e-1 N.
        let err = (f + grad).length();
        assert!(
            err < 1e-3 * f.length() + 2e-5,
            "vertex {i}: f {f}, ∇E {grad}"
        );
    }
}

#[test]
fn hessian_blocks_are_the_force_derivative_under_pure_warp_stretch() {
    hessian_blocks_are_the_force_derivative_under_warp_stretch(&SimParams::default(), 0.01);
}

/// The same for a membrane that stiffens (g = 20 per unit strain up to e = 0.05, so that its
/// tangent is twice k at 5%), stretched 3% (within the growth) and 8% (beyond it): the axial
/// block is the tangent and the transverse one the tension over |w|.
#[test]
fn hessian_blocks_are_the_force_derivative_of_a_stiffening_membrane() {
    let p = stiffening();
    for stretch in [0.03, 0.08] {
        hessian_blocks_are_the_force_derivative_under_warp_stretch(&p, stretch);
    }
}

/// The force and the diagonal Hessian block of an interior vertex under `stretch` along the
/// warp (here x): w_u stretched, w_v unit and orthogonal, so the shear condition is zero, the
/// dropped curvature term vanishes and no stretch condition is compressed.
fn hessian_blocks_are_the_force_derivative_under_warp_stretch(p: &SimParams, stretch: f32) {
    let model = sheet(COTTON, 0.0);
    let x0 = model.packed_positions();
    let x: Vec<Vec4> = x0
        .iter()
        .map(|q| Vec4::new((1.0 + stretch) * q.x, q.y, q.z, q.w))
        .collect();
    let i = 40usize; // an interior vertex
    let csr = model.membrane_csr();
    let vel = vec![Vec4::ZERO; x.len()];
    let force_at = |x: &[Vec4]| {
        let mut f = Vec3::ZERO;
        for &r in &csr.items[csr.offsets[i] as usize..csr.offsets[i + 1] as usize] {
            f += membrane_force(
                p,
                &model.membranes[(r / 4) as usize],
                (r % 4) as usize,
                x,
                &vel,
            );
        }
        f
    };
    // The analytic diagonal block at x (displacements from x: none).
    let zero = vec![Vec4::ZERO; x.len()];
    let mut block = glam::Mat3::ZERO;
    for &r in &csr.items[csr.offsets[i] as usize..csr.offsets[i + 1] as usize] {
        let m: &Membrane = &model.membranes[(r / 4) as usize];
        let role = (r % 4) as usize;
        let (f, blocks) = MembraneStep::at(m, &x, &zero).system(p, m, role, 1.0);
        block += blocks[role];
        // Implicit Euler's force and the explicit integrators' are one function (τ = 0), per
        // triangle (the interior vertex's sum is zero under a uniform stretch): a few ulps.
        let explicit = membrane_force(p, m, role, &x, &vel);
        assert!(
            (f - explicit).length() <= 1e-5 * explicit.length(),
            "{f} vs {explicit}"
        );
    }
    let h = 1e-5f32;
    for axis in 0..3 {
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[i][axis] += h;
        xm[i][axis] -= h;
        // The step as f32 stored it (coordinates of 0.25 m round to 3e-8 m).
        let step = xp[i][axis] - xm[i][axis];
        let column = -(force_at(&xp) - force_at(&xm)) / step;
        // The force is linear in x up to |x|·k/L² terms: central differences err by
        // h²·∂³f ≈ (1e-5)²·k·A·α³ ≈ 1e-10·4000·0.002·4e3 = 3e-6 N/m (the stiffening's growth
        // adds g·k·A·α³·h² of the same size); f32 rounding of the forces (~1e-7 of the
        // triangles' ~1 N, ~20 N stretched 8% and stiffened) over 2e-5 m: under 1 N/m, against
        // diagonal entries of ~1e3–1e4 N/m.
        let err = (column - block.col(axis)).length();
        assert!(
            err < 1e-3 * block.col(axis).length() + 2.0,
            "axis {axis}: {column} vs {}",
            block.col(axis)
        );
    }
}

#[test]
fn rigid_rotation_costs_nothing() {
    let model = sheet(COTTON, 30f32.to_radians());
    let q = Quat::from_euler(glam::EulerRot::XYZ, 0.7, -1.1, 0.4);
    let x: Vec<Vec4> = model
        .packed_positions()
        .iter()
        .map(|p| (q * p.truncate() + Vec3::new(0.3, 1.0, -0.2)).extend(p.w))
        .collect();
    let vel = vec![Vec4::ZERO; x.len()];
    let csr = model.membrane_csr();
    for i in 0..model.len() {
        let mut f = Vec3::ZERO;
        for &r in &csr.items[csr.offsets[i] as usize..csr.offsets[i + 1] as usize] {
            f += membrane_force(
                &SimParams::default(),
                &model.membranes[(r / 4) as usize],
                (r % 4) as usize,
                &x,
                &vel,
            );
        }
        // Coordinates near 1.2 m round by 6e-8 m: edge vectors of 6.25 cm err by 1e-7 m, a
        // strain of 1.7e-6; times k·A·α ≈ 4000·0.002·16 = 125 N that is 2e-4 N per triangle,
        // 1.3e-3 N over a vertex's six. A strain of 1e-3 would give ~0.1 N.
        assert!(f.length() < 1.3e-3, "vertex {i}: {f}");
    }
}

/// The lowest row's drop below its rest height after a 0.4 m × 0.1 m strip of cotton hangs
/// from its top edge for two seconds (implicit Euler, warp `grain_deg` from horizontal).
fn strip_extension(grain_deg: f32, integrator: &str) -> f32 {
    let fabric = format!("preset = \"cotton\"\nmodel = \"membrane\"\ngrain_deg = {grain_deg}");
    hanging_strip_extension(&fabric, integrator, 1.0)
}

/// How far the bottom of a 10 × 40 cm strip of `fabric` (the `[fabric]` table's lines), pinned
/// along its top, sinks under its own weight after two seconds (m), with air damping
/// `air_damping` (1/s).
fn hanging_strip_extension(fabric: &str, integrator: &str, air_damping: f32) -> f32 {
    let toml = format!(
        r#"
[cloth.grid]
width_m = 0.1
height_m = 0.4
columns = 6
rows = 21
center_m = [0.0, 1.0, 0.0]

[fabric]
{fabric}

[[pins]]
edge = "top"

[world]
gravity_m_s2 = [0.0, -9.81, 0.0]
air_damping_per_s = {air_damping}

[solver]
fps = 24
frames = 48
substeps = {substeps}
integrator = "{integrator}"
"#,
        substeps = if integrator == "implicit" {
            "4"
        } else {
            "\"auto\""
        }
    );
    let scene = Scene::parse(&toml, std::path::Path::new("strip.toml")).expect("the strip parses");
    let prep = prepare(&scene).expect("prepares");
    let mut solver = drapekit::cpu::CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut last = Vec::new();
    simulate(&prep, &mut solver, &mut RunStats::default(), |_, s| {
        last = s.positions.clone();
        Ok(())
    })
    .expect("runs");
    let bottom = &last[..6];
    0.8 - bottom.iter().map(|p| p.y).sum::<f32>() / 6.0
}

#[test]
fn bias_cut_strip_stretches_as_its_shear_says() {
    // A strip hanging under its own weight: the load at depth y is ρg(H − y) per width, so a
    // uniaxial stiffness k stretches it by ρgH²/(2k).
    let weight = 0.220 * 9.81 * 0.4 * 0.4 / 2.0;
    let straight = strip_extension(90.0, "implicit");
    let expected = weight / COTTON.warp;
    // Along the warp the membrane has no Poisson coupling, so the strip is uniaxial exactly;
    // the lumped masses put the discrete load at the rows (1/N² = 0.25% for 20 rows) and the
    // strip still moves by ~1e-4 m/s after two seconds: 2%.
    assert!(
        (straight - expected).abs() < 0.02 * expected,
        "straight grain: {straight} m, expected {expected} m"
    );
    // Symplectic Euler (the membrane as explicit forces) at its stable step agrees.
    let symplectic = strip_extension(90.0, "symplectic");
    assert!(
        (symplectic - expected).abs() < 0.02 * expected,
        "straight grain, symplectic: {symplectic} m, expected {expected} m"
    );
    // At 45° the lateral contraction is free except at the pinned top edge, which holds it
    // over about one width (a quarter of the height, carrying 44% of the stretch): the
    // extension lies between 56% and 100% of the lateral-free value.
    let bias = strip_extension(45.0, "implicit");
    let free = weight / COTTON.uniaxial(std::f32::consts::FRAC_PI_4);
    assert!(
        bias > 0.56 * free && bias < free,
        "bias: {bias} m, lateral-free {free} m"
    );
}

/// The jersey's weft hanging under its own weight with `tension = "stiffening"`: at depth y
/// the load is T = ρg·y per width (y from the bottom), the law's strain there solves
/// k·(s + g·s²/2) = T (the load stays under the growth's end), and the extension is its
/// integral over the height; the linear membrane would stretch 1.7 times as far.
#[test]
fn a_stiffening_strip_stretches_as_its_law_says() {
    let fabric = "preset = \"jersey\"\nmodel = \"membrane\"\ntension = \"stiffening\"";
    let (rho, k, large, e) = (0.187f64, 42.92f64, 1716.6f64, 1.0f64 / 6.0);
    let g = (large / k - 1.0) / e;
    let (height, rows) = (0.4f64, 4000);
    let strain = |t: f64| ((1.0 + 2.0 * g * t / k).sqrt() - 1.0) / g;
    let expected = (0..rows)
        .map(|r| {
            strain(rho * 9.81 * height * (r as f64 + 0.5) / rows as f64) * height / rows as f64
        })
        .sum::<f64>() as f32;
    let linear = (rho * 9.81 * height * height / 2.0 / k) as f32;
    assert!(strain(rho * 9.81 * height) < e && expected < 0.6 * linear);
    // As for the straight-grain cotton strip: the rows' lumped load (0.25%) and the strip's
    // last motion after two seconds, 2%. The knit's bounce along the strip (a period of about
    // 0.06 s) is far below the edges' frequency that its damping ratio is set at, and under
    // symplectic Euler 1/s of air damping left it 22% over after two seconds (measured; 4.5% at
    // four): 10/s damps it to e⁻¹⁰ and leaves the static answer as it is.
    for integrator in ["implicit", "symplectic"] {
        let got = hanging_strip_extension(fabric, integrator, 10.0);
        assert!(
            (got - expected).abs() < 0.02 * expected,
            "{integrator}: {got} m, expected {expected} m (linear: {linear} m)"
        );
    }
}

/// The stable-step estimate takes a stiffening membrane at its stiffest: the jersey's warp and
/// weft at their large-strain tangents (7.6 and 40 times the small-strain ones), whose
/// Gershgorin rows grow by that much in their stretch terms (shear and bending unchanged), so
/// ω grows by √7.6–√40 where stretch binds (measured: the step 4.2 times shorter). An estimate
/// that ignored the stiffening (ratio 1), which the stretched knit would overshoot, fails the
/// bound of 2.
#[test]
fn the_stable_step_of_a_stiffening_membrane_is_its_stiffest() {
    let dt = |tension: &str| {
        let toml = format!(
            "[cloth.grid]\nwidth_m = 0.1\nheight_m = 0.4\ncolumns = 6\nrows = 21\n\
             center_m = [0.0, 1.0, 0.0]\n\n[fabric]\npreset = \"jersey\"\nmodel = \"membrane\"\n\
             tension = \"{tension}\"\n\n[solver]\nfps = 24\nframes = 1\n"
        );
        let scene = Scene::parse(&toml, std::path::Path::new("strip.toml")).expect("parses");
        prepare(&scene)
            .expect("prepares")
            .stable_dt
            .expect("a stable step")
    };
    let (linear, stiffening) = (dt("linear"), dt("stiffening"));
    assert!(stiffening < 0.5 * linear, "{stiffening} s vs {linear} s");
}

/// A grid cloth's hinges as a denim membrane with its warp `grain_deg` from the grid's width
/// (x), and the same cloth as springs: (edge direction, membrane hinge, springs hinge) each.
fn denim_hinges(
    grain_deg: f32,
) -> Vec<(
    Vec3,
    drapekit::model::layout::Hinge,
    drapekit::model::layout::Hinge,
)> {
    let scene = |model: &str| {
        let toml = format!(
            "[cloth.grid]\nwidth_m = 0.2\nheight_m = 0.2\ncolumns = 9\nrows = 9\n\
             center_m = [0.0, 1.0, 0.0]\n\n[fabric]\npreset = \"denim\"\nmodel = \"{model}\"\n{}",
            if model == "membrane" {
                format!("grain_deg = {grain_deg}\n")
            } else {
                String::new()
            }
        ) + "\n[solver]\nfps = 24\nframes = 1\n";
        let scene = Scene::parse(&toml, std::path::Path::new("denim.toml")).expect("parses");
        prepare(&scene).expect("prepares").model
    };
    let (membrane, springs) = (scene("membrane"), scene("springs"));
    assert_eq!(membrane.hinges.len(), springs.hinges.len());
    let p = |i: u32| membrane.positions[i as usize];
    (membrane.hinges.iter().zip(&springs.hinges))
        .map(|(m, s)| ((p(m.v[1]) - p(m.v[0])).normalize(), *m, *s))
        .collect()
}

#[test]
fn a_membrane_bends_across_each_hinge_as_its_direction_was_measured() {
    // Denim's strips (W11's hinge rows): 2.424e-5 N·m along the warp, 1.605e-5 along the weft;
    // a hinge's coefficient is 4·B. A hinge whose edge runs across the warp folds what a warp
    // strip bends, and takes k̄ + 3/2·Δ (k̄ the strips' mean, Δ half their difference: what an
    // even spread of hinge directions needs to bend a warp strip at the warp's rigidity,
    // `model::bending`); one along the warp k̄ − 3/2·Δ.
    let [warp, weft] = [2.424e-5f32, 1.605e-5].map(|b| 4.0 * b);
    let (mean, delta) = (0.5 * (warp + weft), 0.5 * (warp - weft));
    let isotropic = 4.0 * 1.97e-5f32;
    for grain_deg in [0.0f32, 90.0] {
        let (s, c) = grain_deg.to_radians().sin_cos();
        let warp_dir = Vec3::new(c, s, 0.0);
        let (mut along, mut across) = (0, 0);
        for (edge, m, s) in denim_hinges(grain_deg) {
            // The springs bend alike every way.
            assert!(
                (s.stiffness / isotropic - 1.0).abs() < 1e-3,
                "{}",
                s.stiffness
            );
            // Edges along or across the warp, to their angle's rounding (1e-5 relative).
            let c = edge.dot(warp_dir).abs();
            let expected = if c > 1.0 - 1e-6 {
                along += 1;
                mean - 1.5 * delta
            } else if c < 1e-6 {
                across += 1;
                mean + 1.5 * delta
            } else {
                // A diagonal of the grid: between the two.
                let k = m.stiffness;
                assert!(k > mean - 1.5 * delta && k < mean + 1.5 * delta, "{k}");
                continue;
            };
            assert!(
                (m.stiffness / expected - 1.0).abs() < 1e-5,
                "{} vs {expected}",
                m.stiffness
            );
            // The rest weight is linear in the coefficient: the same geometry as the springs'.
            let ratio = (m.rest_weight / m.stiffness) / (s.rest_weight / s.stiffness);
            assert!((ratio - 1.0).abs() < 1e-5, "rest weight ratio {ratio}");
        }
        assert!(
            along > 20 && across > 20,
            "{along} along, {across} across the warp"
        );
    }
}

#[test]
fn a_scenes_own_warp_and_weft_bending_set_the_hinges() {
    // Strips of 8e-5 and 4e-5 N·m coefficients: mean 6e-5, half-difference 2e-5, so an edge
    // along the warp takes 6e-5 − 1.5·2e-5 = 3e-5 and one across it 9e-5 (f32: 1e-5 relative).
    let toml = "[cloth.grid]\nwidth_m = 0.2\nheight_m = 0.2\ncolumns = 7\nrows = 7\n\
                center_m = [0.0, 1.0, 0.0]\n\n[fabric]\ndensity_kg_m2 = 0.2\n\
                stretch_stiffness_n_m = 1000.0\nmodel = \"membrane\"\nwarp_stiffness_n_m = 1000.0\n\
                weft_stiffness_n_m = 800.0\nshear_stiffness_n_m = 20.0\n\
                warp_bending_n_m = 8e-5\nweft_bending_n_m = 4e-5\n\n[solver]\nfps = 24\nframes = 1\n";
    let scene = Scene::parse(toml, std::path::Path::new("own.toml")).expect("parses");
    // Without bending_stiffness_n_m the one value is the two's geometric mean.
    let one = scene.fabric.bending_stiffness.expect("the cloth bends");
    assert!((one / (8e-5f32 * 4e-5).sqrt() - 1.0).abs() < 1e-6, "{one}");
    let model = prepare(&scene).expect("prepares").model;
    let p = |i: u32| model.positions[i as usize];
    let (mut along, mut across) = (0, 0);
    for h in &model.hinges {
        let c = (p(h.v[1]) - p(h.v[0])).normalize().dot(Vec3::X).abs();
        let expected = match c {
            c if c > 1.0 - 1e-6 => 3e-5,
            c if c < 1e-6 => 9e-5,
            _ => continue,
        };
        (along, across) = if expected < 6e-5 {
            (along + 1, across)
        } else {
            (along, across + 1)
        };
        assert!(
            (h.stiffness / expected - 1.0).abs() < 1e-5,
            "{} vs {expected}",
            h.stiffness
        );
    }
    assert!(along > 10 && across > 10, "{along} along, {across} across");
}

#[test]
fn hinges_across_seams_bend_by_direction_too() {
    // The straight-grain skirt in denim: its seams run along the grain, so the hinges across
    // them (the model's last ones) fold like the strips of one direction, far from the one
    // value a seam hinge would keep if it missed the grain (4 × 1.97e-5 N·m). Denim's law spans
    // k̄ ± 3/2·Δ = 5.60e-5 to 1.052e-4 (k̄ = 8.06e-5, Δ = 1.64e-5).
    let path = common::fixture("scenes/skirt_straight_grain.toml");
    let src = std::fs::read_to_string(&path).unwrap();
    assert!(src.contains("preset = \"cotton\""));
    let src = src.replacen("preset = \"cotton\"", "preset = \"denim\"", 1);
    let prep = prepare(&Scene::parse(&src, &path).expect("parses")).expect("prepares");
    let seams = prep.garment.as_ref().expect("a pattern").seam_hinges.len();
    assert!(seams > 20, "{seams} seam hinges");
    let hinges = &prep.model.hinges[prep.model.hinges.len() - seams..];
    let (low, high) = (5.60e-5 * (1.0 - 1e-3), 1.052e-4 * (1.0 + 1e-3));
    assert!(hinges.iter().all(|h| (low..=high).contains(&h.stiffness)));
    let mean = hinges.iter().map(|h| h.stiffness).sum::<f32>() / seams as f32;
    let isotropic = 4.0 * 1.97e-5;
    assert!(
        (mean / isotropic - 1.0).abs() > 0.15,
        "seam hinges' mean {mean}"
    );
}

/// Whether the symmetric `n`×`n` matrix `a` (row-major, f64) plus `shift`·I has a Cholesky
/// factor, i.e. its smallest eigenvalue exceeds −`shift`.
fn cholesky_succeeds(mut a: Vec<f64>, n: usize, shift: f64) -> bool {
    for i in 0..n {
        a[i * n + i] += shift;
    }
    for j in 0..n {
        let d = a[j * n + j] - (0..j).map(|k| a[j * n + k].powi(2)).sum::<f64>();
        if d <= 0.0 {
            return false;
        }
        a[j * n + j] = d.sqrt();
        for i in j + 1..n {
            let s = a[i * n + j] - (0..j).map(|k| a[i * n + k] * a[j * n + k]).sum::<f64>();
            a[i * n + j] = s / a[j * n + j];
        }
    }
    true
}

#[test]
fn every_triangle_s_hessian_is_positive_semi_definite_when_sheared_and_compressed() {
    // A sheet moved randomly by up to 1 cm over its 6 cm edges: its triangles sheared,
    // stretched and compressed, where the true Hessian is indefinite (a compressed condition's
    // transverse term, the shear condition's curvature term). The blocks the solve takes leave
    // those terms out, so each triangle's 9×9 matrix is positive semi-definite; with stiffening
    // and buckling too. Its entries are f32 sums of a few products (relative rounding ~1e-6 of
    // the largest entry), which moves its eigenvalues by at most 9 times that: the shift
    // 1e-5·max|H| separates rounding from a dropped-term mistake, whose negative eigenvalues
    // are of the order of the tension (~1e-1 of the stiffness) or the shear stiffness.
    for (name, p) in [
        ("linear", SimParams::default()),
        ("buckling", buckling()),
        ("stiffening", stiffening()),
    ] {
        for seed in [1, 2, 3] {
            let (model, x) = deformed(0.01, seed);
            let zero = vec![Vec4::ZERO; x.len()];
            for (t, m) in model.membranes.iter().enumerate() {
                let mut h = vec![0.0f64; 81];
                for role in 0..3 {
                    let (_, blocks) = MembraneStep::at(m, &x, &zero).system(&p, m, role, 1.0);
                    for (s, block) in blocks.iter().enumerate() {
                        for (c, column) in block.to_cols_array_2d().iter().enumerate() {
                            for (r, &v) in column.iter().enumerate() {
                                h[(3 * role + r) * 9 + 3 * s + c] = v as f64;
                            }
                        }
                    }
                }
                let largest = h.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                assert!(
                    cholesky_succeeds(h, 9, 1e-5 * largest),
                    "{name}, seed {seed}, triangle {t}: not positive semi-definite"
                );
            }
        }
    }
}
