//! `drapekit preview`: a PNG of one frame of a finished run, the garment and the body rendered
//! with wgpu (any adapter, the software one included), framed by a camera preset.

mod camera;
mod render;

pub use camera::{Camera, CameraPreset, PRESET_FOV_DEG};
pub use render::{render, DrawMesh, SHADER};

use crate::atomic_file::write_atomic;
use crate::error::{Error, InputError};
use crate::gpu::{AdapterChoice, GpuContext};
use crate::model::build_body;
use crate::scene::Scene;
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// How the cloth is coloured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ColorMode {
    /// One fabric colour.
    Fabric,
    /// Each triangle's largest principal stretch against frame 0, from blue (0%) to red (at
    /// `max`, a fraction: 0.2 = 20%).
    Strain {
        /// The strain shown in full red.
        max: f32,
    },
}

impl FromStr for ColorMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "fabric" => Ok(ColorMode::Fabric),
            "strain" => Ok(ColorMode::Strain { max: 0.2 }),
            _ => Err(format!("unknown mode {s:?}; use fabric or strain")),
        }
    }
}

/// What to render.
#[derive(Clone, Debug)]
pub struct PreviewOptions {
    /// The frame (`None`: the last one written).
    pub frame: Option<u32>,
    /// The camera.
    pub camera: CameraPreset,
    /// Colouring of the cloth.
    pub mode: ColorMode,
    /// Image width and height in pixels.
    pub size: (u32, u32),
    /// The adapter to render on.
    pub adapter: AdapterChoice,
}

/// Linear RGB of the cloth (also its colour in the glTF export).
pub const FABRIC: Vec3 = Vec3::new(0.10, 0.28, 0.62);
/// Linear RGB of the body.
pub const BODY: Vec3 = Vec3::new(0.62, 0.60, 0.58);

fn bad(path: &Path, problem: impl Into<String>, fix: impl Into<String>) -> Error {
    Error::Input(InputError::new(path, "", problem, fix))
}

/// The frames `frame_NNNN.obj` in a run folder, in order.
fn frames(run: &Path) -> Result<Vec<(u32, PathBuf)>, Error> {
    let entries = std::fs::read_dir(run).map_err(|e| Error::io(run, e))?;
    let mut out: Vec<(u32, PathBuf)> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?;
            let n = name
                .strip_prefix("frame_")?
                .strip_suffix(".obj")?
                .parse()
                .ok()?;
            Some((n, p))
        })
        .collect();
    out.sort();
    Ok(out)
}

/// Positions and triangles of an OBJ frame written by `drapekit run`.
fn load_frame(path: &Path) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), Error> {
    let (models, _) = tobj::load_obj(
        path,
        &tobj::LoadOptions {
            triangulate: true,
            ..Default::default()
        },
    )
    .map_err(|e| {
        bad(
            path,
            format!("cannot read the frame: {e}"),
            "rerun drapekit run",
        )
    })?;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for m in models {
        let base = positions.len() as u32;
        positions.extend(m.mesh.positions.chunks_exact(3).map(Vec3::from_slice));
        triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    Ok((positions, triangles))
}

/// The largest principal stretch − 1 of each triangle from `rest` to `now` (the deformation
/// gradient's largest singular value, computed in each triangle's own plane).
pub fn triangle_strain(rest: &[Vec3], now: &[Vec3], triangles: &[[u32; 3]]) -> Vec<f32> {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| rest[i as usize]);
            let [p, q, r] = t.map(|i| now[i as usize]);
            // An orthonormal frame of the rest triangle.
            let e1 = b - a;
            let u = e1.normalize_or_zero();
            let n = e1.cross(c - a);
            let v = n.cross(e1).normalize_or_zero();
            let (x1, x2, y2) = (e1.dot(u), (c - a).dot(u), (c - a).dot(v));
            if x1.abs() < 1e-12 || y2.abs() < 1e-12 {
                return 0.0;
            }
            // F maps rest edges (x1, 0), (x2, y2) to the current ones: F = D_now · D_rest⁻¹.
            let d1 = q - p;
            let d2 = r - p;
            let f1 = d1 / x1;
            let f2 = (d2 - f1 * x2) / y2;
            // Singular values of the 3×2 F from its 2×2 Gram matrix FᵀF.
            let (g11, g12, g22) = (f1.dot(f1), f1.dot(f2), f2.dot(f2));
            // The larger eigenvalue (g11 + g22)/2 + √(((g11 − g22)/2)² + g12²), written without
            // the cancellation of √(tr²/4 − det) near the identity.
            let half_diff = 0.5 * (g11 - g22);
            let disc = (half_diff * half_diff + g12 * g12).sqrt();
            (0.5 * (g11 + g22) + disc).sqrt() - 1.0
        })
        .collect()
}

/// Blue (0) through white to red (1).
fn ramp(t: f32) -> Vec3 {
    let t = t.clamp(0.0, 1.0);
    let blue = Vec3::new(0.05, 0.20, 0.80);
    let white = Vec3::new(0.85, 0.85, 0.85);
    let red = Vec3::new(0.80, 0.05, 0.03);
    if t < 0.5 {
        blue.lerp(white, 2.0 * t)
    } else {
        white.lerp(red, 2.0 * t - 1.0)
    }
}

/// Renders one frame of the run in `run` (its `summary.json` names the scene) and writes it to
/// `out` as a PNG (atomically).
pub fn preview_run(run: &Path, options: &PreviewOptions, out: &Path) -> Result<(), Error> {
    let summary_path = run.join("summary.json");
    let summary: serde_json::Value = std::fs::read(&summary_path)
        .map_err(|e| Error::io(&summary_path, e))
        .and_then(|b| {
            serde_json::from_slice(&b).map_err(|e| {
                bad(
                    &summary_path,
                    format!("not a drapekit summary: {e}"),
                    "rerun drapekit run",
                )
            })
        })?;
    let scene = match summary["scene"].as_str() {
        Some(path) => Some(Scene::load(Path::new(path))?),
        None => None,
    };
    let fps = summary["fps"].as_f64().unwrap_or(24.0) as f32;
    render_frame(run, scene.as_ref(), fps, options, out)
}

/// Renders one frame of the run in `run`, with `scene`'s body (if any) at its pose at that
/// frame, and writes it to `out` as a PNG (atomically).
pub fn render_frame(
    run: &Path,
    scene: Option<&Scene>,
    fps: f32,
    options: &PreviewOptions,
    out: &Path,
) -> Result<(), Error> {
    let all = frames(run)?;
    let Some((first, first_path)) = all.first().cloned() else {
        return Err(bad(
            run,
            "holds no frame_NNNN.obj",
            "run with [output] obj = true",
        ));
    };
    let (frame, path) = match options.frame {
        None => all.last().cloned().expect("not empty"),
        Some(n) => all.iter().find(|(k, _)| *k == n).cloned().ok_or_else(|| {
            let have: Vec<u32> = all.iter().map(|(k, _)| *k).collect();
            bad(
                run,
                format!("has no frame {n}"),
                format!("use one of {have:?}"),
            )
        })?,
    };
    let (positions, triangles) = load_frame(&path)?;
    let colors = match options.mode {
        ColorMode::Fabric => None,
        ColorMode::Strain { max } => {
            let (rest, _) = load_frame(&first_path)?;
            if first != 0 || rest.len() != positions.len() {
                return Err(bad(
                    run,
                    "strain colours need frame 0 as the rest shape",
                    "rerun with every frame or [output] every dividing the frame",
                ));
            }
            Some(
                triangle_strain(&rest, &positions, &triangles)
                    .into_iter()
                    .map(|s| ramp(s / max))
                    .collect::<Vec<_>>(),
            )
        }
    };
    let cloth = match colors {
        // Flat colours per triangle: every triangle gets its own three vertices.
        Some(tri_colors) => {
            let mut m = DrawMesh::default();
            for (t, c) in triangles.iter().zip(tri_colors) {
                let base = m.positions.len() as u32;
                for &i in t {
                    m.positions.push(positions[i as usize]);
                    m.colors.push(c);
                }
                m.triangles.push([base, base + 1, base + 2]);
            }
            m
        }
        None => DrawMesh {
            colors: vec![FABRIC; positions.len()],
            positions: positions.clone(),
            triangles,
        },
    };
    let (lo, hi) = positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let mut meshes = vec![cloth];
    if let Some(scene) = scene {
        if let Some(settings) = &scene.body {
            let body = build_body(settings, &scene.checker())?;
            let pose = settings.motion.at(frame as f32 / fps);
            meshes.push(DrawMesh {
                positions: (body.mesh.positions.iter())
                    .map(|p| pose.rotation * *p + pose.translation)
                    .collect(),
                colors: vec![BODY; body.mesh.positions.len()],
                triangles: body.mesh.triangles.clone(),
            });
        }
    }
    let (w, h) = options.size;
    let camera = options.camera.framing(lo, hi, w as f32 / h as f32);
    let ctx = GpuContext::new(&options.adapter)?;
    let pixels = render(&ctx, &meshes, &camera, w, h)?;
    write_png(out, &pixels, w, h)
}

/// Encodes RGBA8 pixels as a PNG and writes it atomically.
pub fn write_png(out: &Path, pixels: &[u8], width: u32, height: u32) -> Result<(), Error> {
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        pixels,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )
    .map_err(|e| Error::io(out, std::io::Error::other(e.to_string())))?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    write_atomic(out, &png)
}
