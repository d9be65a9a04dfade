//! Shared test helpers: one device per test binary (the fallback adapter, or the one
//! `DRAPEKIT_TEST_ADAPTER` names), the repository's fixtures, and seeded states.
#![allow(dead_code)] // each test binary uses a different subset

use drapekit::gpu::{AdapterChoice, GpuContext};
use drapekit::solver::ParticleState;
use glam::Vec4;
use std::sync::OnceLock;

/// The adapter the GPU tests run on: `DRAPEKIT_TEST_ADAPTER=auto` (wgpu's high-performance
/// adapter, or `WGPU_ADAPTER_NAME`'s), `=<part of an adapter name>`, or unset (or `fallback`):
/// wgpu's fallback (software) adapter, e.g. Mesa lavapipe.
pub fn test_adapter() -> AdapterChoice {
    match std::env::var("DRAPEKIT_TEST_ADAPTER") {
        Ok(name) if !name.trim().is_empty() => name.trim().parse().unwrap(),
        _ => AdapterChoice::Fallback,
    }
}

/// Whether the tests run on the fallback adapter. Bounds that are exact there (lavapipe rounds
/// as the CPU twin does, without contracting a·b + c into an FMA) stay exact there; on any
/// other adapter the tests use bounds derived from what WGSL allows (FMA contraction, 2.5 ULP
/// for division and `inverseSqrt`), stated at each assertion.
pub fn on_fallback() -> bool {
    test_adapter() == AdapterChoice::Fallback
}

/// The test adapter's device, shared by every test in this binary because creating a device
/// per test is slow on lavapipe and can exhaust threads.
/// Returns `None` (and says so) without an adapter; under `CI=true` that is a failure.
pub fn gpu() -> Option<&'static GpuContext> {
    static CTX: OnceLock<Result<GpuContext, String>> = OnceLock::new();
    let ctx = CTX.get_or_init(|| {
        if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
            // Silences the Vulkan loader's harmless XDG_RUNTIME_DIR warnings.
            std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
        }
        let ctx = GpuContext::new(&test_adapter()).map_err(|e| e.to_string());
        if let Ok(ctx) = &ctx {
            eprintln!("GPU tests on {}", ctx.report().describe());
        }
        ctx
    });
    match ctx {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            let ci = std::env::var("CI")
                .map(|v| v == "true" || v == "1")
                .unwrap_or(false);
            assert!(
                !ci,
                "CI=true but no GPU adapter ({}): {e}\n\
                 install Mesa lavapipe (apt-get install -y mesa-vulkan-drivers libvulkan1), \
                 or check DRAPEKIT_TEST_ADAPTER against `drapekit info`",
                test_adapter()
            );
            eprintln!("SKIPPED (no GPU adapter, not under CI): {e}");
            None
        }
    }
}

/// A tiny deterministic generator (xorshift) so that tests need no extra crate.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }
    /// Uniform in [-1, 1).
    pub fn signed(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 23) as f32 - 1.0
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f32 {
        0.5 * (self.signed() + 1.0)
    }
    pub fn vec3(&mut self, scale: f32) -> glam::Vec3 {
        glam::Vec3::new(self.signed(), self.signed(), self.signed()) * scale
    }
}

/// `state` with every free particle displaced by up to `dx` m and moving at up to `dv` m/s.
pub fn perturbed(state: &ParticleState, seed: u64, dx: f32, dv: f32) -> ParticleState {
    let mut rng = Rng::new(seed);
    let positions = state
        .positions
        .iter()
        .map(|p| (p.truncate() + rng.vec3(dx)).extend(p.w))
        .collect();
    let velocities = state
        .velocities
        .iter()
        .zip(&state.positions)
        .map(|(_, p)| {
            if p.w == 0.0 {
                Vec4::ZERO
            } else {
                rng.vec3(dv).extend(0.0)
            }
        })
        .collect();
    ParticleState {
        positions,
        velocities,
    }
}

/// Largest component-wise |a − b| over two vec4 lists (xyz only).
pub fn max_abs_diff(a: &[Vec4], b: &[Vec4]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x.truncate() - y.truncate()).abs().max_element())
        .fold(0.0, f32::max)
}

/// Largest |v| over a vec4 list (xyz only).
pub fn max_norm(a: &[Vec4]) -> f32 {
    a.iter().map(|v| v.truncate().length()).fold(0.0, f32::max)
}

/// The repository root whose fixtures/ the tests read: `DRAPEKIT_REPO` if set, else the
/// current directory when it holds fixtures/ (a compiled test binary run from a copy of the
/// repository on another machine), else `CARGO_MANIFEST_DIR` (at run time, then as compiled).
pub fn repo_root() -> std::path::PathBuf {
    if let Some(dir) = std::env::var_os("DRAPEKIT_REPO") {
        return dir.into();
    }
    if let Ok(cwd) = std::env::current_dir() {
        if cwd.join("fixtures").join("scenes").is_dir() {
            return cwd;
        }
    }
    std::env::var_os("CARGO_MANIFEST_DIR")
        .map(Into::into)
        .unwrap_or_else(|| env!("CARGO_MANIFEST_DIR").into())
}

/// Path of a shipped fixture.
pub fn fixture(rel: &str) -> std::path::PathBuf {
    repo_root().join("fixtures").join(rel)
}

/// Asserts that `pixels` (RGBA, `w` × `h`), rendered by the test binary `test`'s `golden`
/// test, match the golden image `fixtures/<rel>`; with `DRAPEKIT_BLESS` set, first writes them
/// there (then look at the image, and commit it). On a mismatch the render is left in the
/// temporary folder, and the message says where.
pub fn assert_golden(pixels: &[u8], (w, h): (u32, u32), rel: &str, test: &str) {
    let golden = fixture(rel);
    if std::env::var_os("DRAPEKIT_BLESS").is_some() {
        drapekit::preview::write_png(&golden, pixels, w, h).unwrap();
    }
    let want = image::open(&golden)
        .unwrap_or_else(|e| {
            panic!(
                "{}: {e}; render it with DRAPEKIT_BLESS=1 cargo test --release --test {test} \
                 golden, look at it, and commit it",
                golden.display()
            )
        })
        .to_rgba8();
    assert_eq!((want.width(), want.height()), (w, h));
    // Lavapipe rasterises deterministically, but another Mesa/LLVM may round a lit colour by
    // a level or two and resolve a 2×2-supersampled edge sample, or a texture's filtering, the
    // other way (one of four samples: up to a quarter of the edge's contrast). So: every pixel
    // within 3 levels, except at most 1% of them (the silhouettes cover about 8% of these
    // images); and none off by more than half the range, which a missing mesh or texture, a
    // wrong colour map, a moved camera or lost occlusion exceeds.
    let mut off = 0;
    let mut worst = 0;
    for (a, b) in pixels.chunks_exact(4).zip(want.as_raw().chunks_exact(4)) {
        let d = (0..3)
            .map(|c| (a[c] as i32 - b[c] as i32).abs())
            .max()
            .unwrap();
        worst = worst.max(d);
        off += (d > 3) as u32;
    }
    let allowed = w * h / 100;
    if off > allowed || worst > 128 {
        let stem = golden.file_stem().unwrap().to_string_lossy();
        let actual = std::env::temp_dir().join(format!("drapekit-golden-{stem}-actual.png"));
        drapekit::preview::write_png(&actual, pixels, w, h).unwrap();
        panic!(
            "{off} pixels differ by more than 3 levels (allowed {allowed}), worst {worst}; \
             this render is in {}",
            actual.display()
        );
    }
}

/// A 1 m × 0.6 m sheet in the xy plane at z = 0, 20 × 12 quads.
pub fn sheet(color: glam::Vec3) -> drapekit::preview::DrawMesh {
    let (nx, ny) = (21u32, 13u32);
    let mut m = drapekit::preview::DrawMesh::default();
    for j in 0..ny {
        for i in 0..nx {
            m.positions.push(glam::Vec3::new(
                i as f32 / (nx - 1) as f32 - 0.5,
                0.6 * j as f32 / (ny - 1) as f32 + 1.0,
                0.0,
            ));
            m.colors.push(color);
        }
    }
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let a = j * nx + i;
            m.triangles.push([a, a + 1, a + nx + 1]);
            m.triangles.push([a, a + nx + 1, a + nx]);
        }
    }
    m
}

/// Runs the drapekit binary with `args` and waits for it.
pub fn drapekit(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap()
}

/// A fresh (removed) folder under the temporary directory, unique to this process, `tag`
/// (the test file) and `name`.
pub fn out_dir(tag: &str, name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("drapekit-{tag}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// One CSV line's cells: commas inside double quotes belong to the cell (the commands write no
/// quote inside a quoted cell).
pub fn split_csv(line: &str) -> Vec<String> {
    let (mut cells, mut cell, mut quoted) = (Vec::new(), String::new(), false);
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => cells.push(std::mem::take(&mut cell)),
            c => cell.push(c),
        }
    }
    cells.push(cell);
    cells
}

/// The CSV as a header and rows of named cells.
pub fn read_csv(
    path: &std::path::Path,
    last: &str,
) -> (Vec<String>, Vec<std::collections::HashMap<String, String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = split_csv(lines.next().unwrap());
    assert_eq!(header.last().map(String::as_str), Some(last));
    let rows = lines
        .map(|line| {
            let cells = split_csv(line);
            assert_eq!(cells.len(), header.len(), "{line}");
            header.iter().cloned().zip(cells).collect()
        })
        .collect();
    (header, rows)
}

/// A cell that must hold a finite number.
pub fn finite(row: &std::collections::HashMap<String, String>, column: &str) -> f64 {
    let v: f64 = row[column]
        .parse()
        .unwrap_or_else(|_| panic!("{column} = {:?} in {row:?}", row[column]));
    assert!(v.is_finite(), "{column} = {v} in {row:?}");
    v
}

/// The shipped two-body scene with its clamp closed (frame 8, 0.33 s: the clamp's underside
/// 4.5 mm above the table's top at y = 0), and a state with the cloth flattened onto the table
/// and every particle lifted by a random height from −1.5 to 6 mm, moving at up to 0.5 m/s:
/// particles in and out of both bodies' 3 mm contact shells, under the clamp and beside it.
/// Returns the prepared scene, the state and that frame's first substep.
pub fn pinched() -> (
    drapekit::sim::Prepared,
    ParticleState,
    drapekit::model::layout::SubstepParams,
) {
    pinched_with("")
}

/// `pinched` with `fabric` added to the scene's `[fabric]` table (see `scene_with_fabric`).
pub fn pinched_with(
    fabric: &str,
) -> (
    drapekit::sim::Prepared,
    ParticleState,
    drapekit::model::layout::SubstepParams,
) {
    let scene = scene_with_fabric("scenes/cloth_pinched.toml", fabric);
    let prep = drapekit::sim::prepare(&scene).unwrap();
    let flat = ParticleState {
        positions: (prep.model.positions.iter().zip(&prep.model.masses))
            .map(|(p, &m)| glam::Vec3::new(p.x, 0.0, p.z).extend(1.0 / m))
            .collect(),
        velocities: vec![Vec4::ZERO; prep.model.len()],
    };
    let mut state = perturbed(&flat, 17, 0.0, 0.5);
    let mut rng = Rng::new(18);
    for p in &mut state.positions {
        p.y = 2.25e-3 + 3.75e-3 * rng.signed();
    }
    let step = drapekit::sim::substep_params(&prep, 8)[0];
    (prep, state, step)
}

/// The shipped scene `rel` with the lines `fabric` added at the top of its `[fabric]` table
/// (e.g. `model = "membrane"`), parsed as from its own file so that its relative paths resolve.
pub fn scene_with_fabric(rel: &str, fabric: &str) -> drapekit::scene::Scene {
    let path = fixture(rel);
    let src = std::fs::read_to_string(&path).unwrap();
    assert!(src.contains("\n[fabric]\n"), "{rel} has no [fabric] table");
    let src = src.replacen("\n[fabric]\n", &format!("\n[fabric]\n{fabric}\n"), 1);
    drapekit::scene::Scene::parse(&src, &path).unwrap()
}

/// The fabric as a membrane (its warp, weft and shear from the scene's preset) whose warp runs
/// at 30° to each panel's x axis: `scene_with_fabric`'s lines for a scene with a preset.
pub const MEMBRANE_GRAIN_30: &str = "model = \"membrane\"\ngrain_deg = 30.0";

/// A closed cube of half-size `h` m at the origin as OBJ text (quads), and its corners in
/// the order of its `v` records.
pub fn box_obj(h: f32) -> (String, Vec<glam::Vec3>) {
    let corners: Vec<glam::Vec3> = (0..8)
        .map(|i| {
            let s = |b: u32| if i & b != 0 { h } else { -h };
            glam::Vec3::new(s(1), s(2), s(4))
        })
        .collect();
    let faces = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    let mut s: String = (corners.iter())
        .map(|v| format!("v {} {} {}\n", v.x, v.y, v.z))
        .collect();
    for f in faces {
        s.push_str(&format!(
            "f {} {} {} {}\n",
            f[0] + 1,
            f[1] + 1,
            f[2] + 1,
            f[3] + 1
        ));
    }
    (s, corners)
}

/// The built-in mannequin, moving from t = 0: the `[body]` section of a test scene.
pub struct Mannequin {
    /// `"walk"` or `"arms-down"`.
    pub animation: &'static str,
    /// Seconds over which the motion starts from the rest pose.
    pub transition_s: f64,
    /// The distance field's cell, m.
    pub sdf_resolution_m: f64,
    /// Coulomb friction, where the test needs it.
    pub friction: Option<f64>,
}

impl Mannequin {
    /// The section's TOML text (3 mm thick, standing at the origin).
    pub fn body_toml(&self) -> String {
        let mut text = format!(
            "[body]\nshape = \"mannequin\"\ncenter_m = [0.0, 0.0, 0.0]\nanimation = \"{}\"\n\
             motion_start_s = 0.0\ntransition_s = {:?}\nthickness_m = 0.003\n\
             sdf_resolution_m = {:?}\n",
            self.animation, self.transition_s, self.sdf_resolution_m
        );
        if let Some(mu) = self.friction {
            text += &format!("friction = {mu:?}\n");
        }
        text
    }
}

/// `compression = "buckling"`: `scene_with_fabric`'s line for springs that buckle.
pub const BUCKLING: &str = "compression = \"buckling\"";

/// How many of the model's springs are compressed past their Euler onset
/// (`SimParams::euler_onset` / rest length) at `positions`: the buckled branch's share of a
/// test.
pub fn buckled_springs(prep: &drapekit::sim::Prepared, positions: &[glam::Vec4]) -> usize {
    let onset_area = prep.params.euler_onset;
    (prep.model.springs.iter())
        .filter(|s| {
            let [a, b] = s.ends.map(|e| positions[e as usize].truncate());
            a.distance(b) - s.rest_length < -onset_area / s.rest_length
        })
        .count()
}

/// How many of the membrane's warp and weft conditions are compressed past their Euler onset
/// (`SimParams::membrane_onset` over the condition's stiffness) at `positions`.
pub fn buckled_conditions(prep: &drapekit::sim::Prepared, positions: &[glam::Vec4]) -> usize {
    let zero = vec![glam::Vec4::ZERO; positions.len()];
    let onset = prep.params.membrane_onset;
    (prep.model.membranes.iter())
        .map(|m| {
            let step = drapekit::cpu::membrane::MembraneStep::at(m, positions, &zero);
            (0..2)
                .filter(|&c| step.stretch(c) < -onset / m.stiffness[c])
                .count()
        })
        .sum()
}

/// A membrane that stiffens, for parity: `tension = "stiffening"` with large-strain tangents
/// twice the cotton membrane's warp and 1.3 times its weft (4,033 and 4,070 N/m), near the
/// denim preset's 1.8 and 1.6 and unequal, so that a warp/weft swap shows. Ten times (the knit's weft stiffens 40-fold) made the solve stages'
/// row-to-row bounds on the coarsest level carry past a tenth of the correction, where they
/// no longer tell a wrong kernel from rounding.
pub const STIFFENING: &str = "tension = \"stiffening\"\nwarp_large_strain_stiffness_n_m = 8066.0\n\
                              weft_large_strain_stiffness_n_m = 5291.0";

/// How many of the model's membrane conditions are stretched within the stiffening law's
/// growth (0 < s ≤ e) and beyond it (s > e, `SimParams::stiffening`) at `positions`.
pub fn stiffened_conditions(
    prep: &drapekit::sim::Prepared,
    positions: &[glam::Vec4],
) -> (usize, usize) {
    let zero = vec![glam::Vec4::ZERO; positions.len()];
    let end = prep.params.stiffening[2];
    let (mut within, mut beyond) = (0, 0);
    for m in &prep.model.membranes {
        let step = drapekit::cpu::membrane::MembraneStep::at(m, positions, &zero);
        for c in 0..2 {
            let s = step.stretch(c);
            within += usize::from(s > 0.0 && s <= end);
            beyond += usize::from(s > end);
        }
    }
    (within, beyond)
}
