//! Rendering the frames of a run folder: reads `frame_NNNN.obj`, colours the cloth by mode, adds
//! the body at its pose, the seams and the legend. One device and one body for many frames.

use super::camera::CameraChoice;
use super::colors::{
    penetration_legend, strain_legend, triangle_strain, ColorMode, PenetrationScale, BODY, FABRIC,
};
use super::legend::draw_legend;
use super::render::{render, DrawMesh};
use super::seams::{seam_ribbons, seam_segments};
use crate::body::exact::ExactBody;
use crate::body::Body;
use crate::error::{Error, InputError};
use crate::gpu::{AdapterChoice, GpuContext};
use crate::model::build_body;
use crate::scene::{BodySettings, Scene};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// How one image looks.
#[derive(Clone, Debug)]
pub struct Look {
    /// The camera.
    pub camera: CameraChoice,
    /// Colouring of the cloth.
    pub mode: ColorMode,
    /// Image width and height in pixels.
    pub size: (u32, u32),
    /// The strain shown in full red (0.2 = 20%).
    pub strain_max: f32,
    /// Draw the seams.
    pub seams: bool,
    /// Draw the colour legend of the strain and penetration modes.
    pub legend: bool,
}

pub(super) fn bad(path: &Path, problem: impl Into<String>, fix: impl Into<String>) -> Error {
    Error::Input(InputError::new(path, "", problem, fix))
}

/// The frames `frame_NNNN.obj` in a run folder, in order.
pub fn frames(run: &Path) -> Result<Vec<(u32, PathBuf)>, Error> {
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

/// Positions (in file order, which is the particle order of drapekit's frames) and triangles
/// (polygons as fans) of an OBJ file. Only `v` and `f` records are read.
pub fn read_obj(path: &Path) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let broken = |n: usize| {
        bad(
            path,
            format!("line {}: not an OBJ vertex or face", n + 1),
            "rerun drapekit run to rewrite the frame",
        )
    };
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let xyz: Vec<f32> = words.take(3).filter_map(|w| w.parse().ok()).collect();
                if xyz.len() != 3 {
                    return Err(broken(n));
                }
                positions.push(Vec3::from_slice(&xyz));
            }
            Some("f") => {
                let mut ids = Vec::new();
                for w in words {
                    let i: i64 = (w.split('/').next())
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| broken(n))?;
                    // 1-based, or negative: counted back from the last vertex.
                    let i = if i < 0 {
                        positions.len() as i64 + i
                    } else {
                        i - 1
                    };
                    if i < 0 || i >= positions.len() as i64 {
                        return Err(broken(n));
                    }
                    ids.push(i as u32);
                }
                for k in 1..ids.len().saturating_sub(1) {
                    triangles.push([ids[0], ids[k], ids[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok((positions, triangles))
}

/// The bounding box of `points`.
pub fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    points.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// A written frame: its number, the particles' positions and the triangles.
pub type LoadedFrame = (u32, Vec<Vec3>, Vec<[u32; 3]>);

/// Renders frames of one run folder.
pub struct Previewer<'a> {
    ctx: GpuContext,
    run: PathBuf,
    scene: Option<&'a Scene>,
    fps: f32,
    body: Option<(Body, &'a BodySettings)>,
    exact: Option<ExactBody>,
    rest: Option<Vec<Vec3>>,
    seams: Option<Vec<[u32; 2]>>,
}

impl<'a> Previewer<'a> {
    /// A previewer of the frames in `run`, with `scene`'s body (if any) posed at each frame's
    /// time (`fps` frames per second), rendering on `adapter`.
    pub fn new(
        run: &Path,
        scene: Option<&'a Scene>,
        fps: f32,
        adapter: &AdapterChoice,
    ) -> Result<Self, Error> {
        let body = match scene.and_then(|s| s.body.as_ref().map(|b| (s, b))) {
            Some((s, settings)) => Some((build_body(settings, &s.checker())?, settings)),
            None => None,
        };
        Ok(Previewer {
            ctx: GpuContext::new(adapter)?,
            run: run.to_path_buf(),
            scene,
            fps,
            body,
            exact: None,
            rest: None,
            seams: None,
        })
    }

    /// The frame numbers written so far.
    pub fn frame_numbers(&self) -> Result<Vec<u32>, Error> {
        Ok(frames(&self.run)?.into_iter().map(|(n, _)| n).collect())
    }

    /// The frame `n` (`None`: the last), as its number, positions and triangles.
    pub fn load(&self, n: Option<u32>) -> Result<LoadedFrame, Error> {
        let all = frames(&self.run)?;
        let found = match n {
            None => all.last().cloned(),
            Some(n) => all.iter().find(|(k, _)| *k == n).cloned(),
        };
        let Some((k, path)) = found else {
            if all.is_empty() {
                return Err(bad(
                    &self.run,
                    "holds no frame_NNNN.obj",
                    "run with OBJ frames ([output] obj = true, or \"obj\" in formats)",
                ));
            }
            let have: Vec<u32> = all.iter().map(|(k, _)| *k).collect();
            return Err(bad(
                &self.run,
                format!("has no frame {}", n.unwrap_or(0)),
                format!("use one of {have:?}"),
            ));
        };
        let (p, t) = read_obj(&path)?;
        Ok((k, p, t))
    }

    /// Frame 0, the strain's rest shape, read once.
    fn rest(&mut self, particles: usize) -> Result<&[Vec3], Error> {
        if self.rest.is_none() {
            let first = frames(&self.run)?.into_iter().next();
            let rest = match first {
                Some((0, path)) => read_obj(&path)?.0,
                _ => Vec::new(),
            };
            self.rest = Some(rest);
        }
        let rest = self.rest.as_deref().unwrap_or_default();
        if rest.len() != particles {
            return Err(bad(
                &self.run,
                "strain colours need frame 0 (frame_0000.obj) as the rest shape",
                "rerun the scene so that frame 0 is written (it always is with OBJ frames on)",
            ));
        }
        Ok(rest)
    }

    /// The cloth coloured by `look.mode`, and the legend that explains the colours.
    fn cloth(
        &mut self,
        frame: u32,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        look: &Look,
    ) -> Result<(DrawMesh, Option<super::colors::Legend>), Error> {
        match look.mode {
            ColorMode::Fabric => Ok((
                DrawMesh {
                    positions: positions.to_vec(),
                    colors: vec![FABRIC; positions.len()],
                    triangles: triangles.to_vec(),
                },
                None,
            )),
            ColorMode::Strain => {
                let max = look.strain_max;
                let strain = triangle_strain(self.rest(positions.len())?, positions, triangles);
                // Flat colours per triangle: every triangle gets its own three vertices.
                let mut m = DrawMesh::default();
                for (t, s) in triangles.iter().zip(strain) {
                    let base = m.positions.len() as u32;
                    for &i in t {
                        m.positions.push(positions[i as usize]);
                        m.colors.push(super::colors::strain_ramp(s / max));
                    }
                    m.triangles.push([base, base + 1, base + 2]);
                }
                Ok((m, Some(strain_legend(max))))
            }
            ColorMode::Penetration => {
                let Some((body, settings)) = &self.body else {
                    return Err(bad(
                        &self.run,
                        "penetration colours need a body, and the run's scene has no [body]",
                        "use --mode fabric or --mode strain",
                    ));
                };
                if self.exact.is_none() {
                    let exact = ExactBody::new(&body.mesh).map_err(|e| {
                        Error::Gpu(format!("cannot measure distances to the body: {e}"))
                    })?;
                    self.exact = Some(exact);
                }
                let exact = self.exact.as_ref().expect("built above");
                let pose = settings.motion.at(frame as f32 / self.fps);
                let inverse = pose.rotation.inverse();
                let scale = PenetrationScale::for_thickness(settings.thickness);
                let colors = (positions.iter())
                    .map(|p| scale.color(exact.query(inverse * (*p - pose.translation)).0))
                    .collect();
                Ok((
                    DrawMesh {
                        positions: positions.to_vec(),
                        colors,
                        triangles: triangles.to_vec(),
                    },
                    Some(penetration_legend(scale)),
                ))
            }
        }
    }

    /// The seam segments of the scene's pattern (none for other cloth), built once.
    fn seam_segments(&mut self) -> Result<&[[u32; 2]], Error> {
        if self.seams.is_none() {
            let garment = match self.scene {
                Some(s) => s.build_garment()?,
                None => None,
            };
            self.seams = Some(garment.as_ref().map(seam_segments).unwrap_or_default());
        }
        Ok(self.seams.as_deref().unwrap_or_default())
    }

    /// The box a preset camera frames: the cloth, and the body where it lies near the cloth's
    /// box (a T-shirt's head, a skirt's hips, not the whole mannequin).
    pub fn framing_box(&self, frame: u32, cloth: &[Vec3]) -> (Vec3, Vec3) {
        let (lo, hi) = bounds(cloth);
        let Some((body, settings)) = &self.body else {
            return (lo, hi);
        };
        // Up by 40% of the cloth's height (a T-shirt's head), elsewhere by 10% of its size.
        let side = Vec3::splat(0.1 * (hi - lo).max_element());
        let (near_lo, near_hi) = (lo - side, hi + side + Vec3::Y * 0.4 * (hi.y - lo.y));
        let pose = settings.motion.at(frame as f32 / self.fps);
        let near: Vec<Vec3> = (body.mesh.positions.iter())
            .map(|p| pose.rotation * *p + pose.translation)
            .filter(|p| p.cmpge(near_lo).all() && p.cmple(near_hi).all())
            .collect();
        if near.is_empty() {
            return (lo, hi);
        }
        let (b_lo, b_hi) = bounds(&near);
        (lo.min(b_lo), hi.max(b_hi))
    }

    /// Renders frame `n` (`None`: the last) as RGBA8 sRGB pixels of `look.size`. A preset
    /// camera frames `framing` when given (a fixed box for an animation), else the cloth.
    pub fn image(
        &mut self,
        n: Option<u32>,
        look: &Look,
        framing: Option<(Vec3, Vec3)>,
    ) -> Result<Vec<u8>, Error> {
        let (frame, positions, triangles) = self.load(n)?;
        let (cloth, legend) = self.cloth(frame, &positions, &triangles, look)?;
        let (w, h) = look.size;
        let (lo, hi) = framing.unwrap_or_else(|| self.framing_box(frame, &positions));
        let camera = look.camera.camera(lo, hi, w as f32 / h as f32);
        let mut meshes = vec![cloth];
        if look.seams {
            let segments = self.seam_segments()?.to_vec();
            let width_px = (h as f32 / 400.0).max(2.0);
            meshes.push(seam_ribbons(&positions, &segments, &camera, h, width_px));
        }
        if let Some((body, settings)) = &self.body {
            let pose = settings.motion.at(frame as f32 / self.fps);
            meshes.push(DrawMesh {
                positions: (body.mesh.positions.iter())
                    .map(|p| pose.rotation * *p + pose.translation)
                    .collect(),
                colors: vec![BODY; body.mesh.positions.len()],
                triangles: body.mesh.triangles.clone(),
            });
        }
        let mut pixels = render(&self.ctx, &meshes, &camera, w, h)?;
        if let Some(legend) = legend.filter(|_| look.legend) {
            draw_legend(&mut pixels, w, h, &legend);
        }
        Ok(pixels)
    }
}
