//! Rendering the frames of a run folder: reads `frame_NNNN.obj`, colours the cloth by mode, adds
//! the bodies at their poses, the seams and the legend. One device and one set of bodies for many frames.

use super::camera::CameraChoice;
use super::colors::{
    panel_color, penetration_legend, strain_legend, strain_ramp, triangle_strain, ColorMode,
    PenetrationScale, BODY, FABRIC,
};
use super::legend::draw_legend;
use super::obj_frame::{frames, read_obj, FrameMesh};
use super::occlusion::ambient_occlusion;
use super::render::{render_textured, DrawMesh, FabricTexture};
use super::seams::{seam_ribbons, seam_segments};
use crate::body::deform::Deformation;
use crate::body::exact::ExactBody;
use crate::body::Body;
use crate::error::{Error, InputError};
use crate::gpu::{AdapterChoice, GpuContext};
use crate::metrics::bounds;
use crate::model::build_deforming;
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
    /// Fabric colours per panel (linear RGB; empty: the built-in palette).
    pub colors: Vec<Vec3>,
    /// The checker's square size in pattern coordinates in m (0: none).
    pub checker: f32,
    /// Darken folds and creases by ambient occlusion (the fabric look; the strain and
    /// penetration colours are left exact).
    pub occlusion: bool,
    /// An image of the fabric over the pattern coordinates, in fabric mode.
    pub texture: Option<crate::scene::TextureSetting>,
}

pub(super) fn bad(path: &Path, problem: impl Into<String>, fix: impl Into<String>) -> Error {
    Error::Input(InputError::new(path, "", problem, fix))
}

/// The frame's pattern coordinates turned so that u runs along each panel's warp (its grain
/// angle from the panel's x axis), so that the checker and a fabric image follow the grain as a
/// print on the cloth would: a bias-cut panel shows its checks at 45°. Panels do not share
/// particles, so a vertex takes any of its triangles' panel.
fn along_grain(f: &FrameMesh, grain: &crate::scene::Grain) -> Vec<glam::Vec2> {
    let angles: Vec<f32> = (f.group_names.iter())
        .map(|name| grain.panels.get(name).copied().unwrap_or(grain.default))
        .collect();
    let mut angle = vec![grain.default; f.uv.len()];
    for (t, &g) in f.triangles.iter().zip(&f.groups) {
        for &i in t {
            if let (Some(a), Some(&panel)) = (angle.get_mut(i as usize), angles.get(g as usize)) {
                *a = panel;
            }
        }
    }
    (f.uv.iter().zip(angle))
        .map(|(&uv, a)| glam::Vec2::from_angle(-a).rotate(uv))
        .collect()
}

/// Renders frames of one run folder.
pub struct Previewer<'a> {
    ctx: GpuContext,
    run: PathBuf,
    scene: Option<&'a Scene>,
    fps: f32,
    bodies: Vec<(Body, &'a BodySettings)>,
    /// Each body's deformation, if it deforms (parallel to `bodies`).
    deforms: Vec<Option<Deformation>>,
    exact: Option<Vec<ExactBody>>,
    rest: Option<Vec<Vec3>>,
    seams: Option<Vec<[u32; 2]>>,
    /// The run's frames as its summary lists them (`None`: every frame file in the folder).
    listed: Option<Vec<(u32, PathBuf)>>,
    /// The scene's garment's seams welded, for normals that run smooth across them.
    weld: Option<Option<crate::pattern::weld::Weld>>,
    /// The fabric image, read once.
    texture: Option<(crate::scene::TextureSetting, FabricTexture)>,
    /// The last frame's ambient occlusion, which does not depend on the camera (a turntable
    /// renders one frame many times).
    occlusion: Option<(u32, Vec<Vec<[f32; 2]>>)>,
}

impl<'a> Previewer<'a> {
    /// A previewer of the frames in `run`, with `scene`'s bodies (if any) posed at each frame's
    /// time (`fps` frames per second), rendering on `adapter`.
    pub fn new(
        run: &Path,
        scene: Option<&'a Scene>,
        fps: f32,
        adapter: &AdapterChoice,
    ) -> Result<Self, Error> {
        let (mut bodies, mut deforms) = (Vec::new(), Vec::new());
        if let Some(s) = scene {
            for (i, settings) in s.bodies.iter().enumerate() {
                let (body, deform) = build_deforming(settings, &s.checker(), &s.body_table(i))?;
                bodies.push((body, settings));
                deforms.push(deform);
            }
        }
        Ok(Previewer {
            ctx: GpuContext::new(adapter)?,
            run: run.to_path_buf(),
            scene,
            fps,
            bodies,
            deforms,
            exact: None,
            rest: None,
            seams: None,
            listed: None,
            weld: None,
            texture: None,
            occlusion: None,
        })
    }

    /// Shows only these frames (the run's, from its summary), not every frame file in the folder.
    pub fn use_frames(&mut self, frames: Vec<(u32, PathBuf)>) {
        self.listed = Some(frames);
    }

    /// The frames to show, in order.
    pub fn frame_files(&self) -> Result<Vec<(u32, PathBuf)>, Error> {
        match &self.listed {
            Some(list) => Ok(list.clone()),
            None => frames(&self.run),
        }
    }

    /// The frame `n` (`None`: the last).
    pub fn load(&self, n: Option<u32>) -> Result<FrameMesh, Error> {
        let all = self.frame_files()?;
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
        let mut m = read_obj(&path)?;
        m.number = k;
        if let Some(s) = self.scene {
            m.uv = along_grain(&m, &s.grain);
        }
        Ok(m)
    }

    /// Frame 0, the strain's rest shape, read once.
    fn rest(&mut self, particles: usize) -> Result<&[Vec3], Error> {
        if self.rest.is_none() {
            let first = self.frame_files()?.into_iter().next();
            let rest = match first {
                Some((0, path)) => read_obj(&path)?.positions,
                _ => Vec::new(),
            };
            self.rest = Some(rest);
        }
        let rest = self.rest.as_deref().unwrap_or_default();
        if rest.is_empty() {
            return Err(bad(
                &self.run,
                "strain colours need frame 0 (frame_0000.obj) as the rest shape",
                "rerun the scene so that frame 0 is written (it always is with OBJ frames on)",
            ));
        }
        if rest.len() != particles {
            // Frame 0 is there, but of another cloth: the folder mixes two runs' frames.
            return Err(bad(
                &self.run.join("frame_0000.obj"),
                format!(
                    "frame 0 has {} vertices and this frame {particles}: they are not one run's, \
                     so frame 0 is no rest shape for its strain",
                    rest.len()
                ),
                "rerun the scene into an empty folder (or with --overwrite)",
            ));
        }
        Ok(rest)
    }

    /// The cloth coloured by `look.mode`, and the legend that explains the colours.
    fn cloth(
        &mut self,
        f: &FrameMesh,
        look: &Look,
    ) -> Result<(DrawMesh, Option<super::colors::Legend>), Error> {
        let smooth_normals = self.smooth_normals(f)?;
        let mesh = |colors: Vec<Vec3>| DrawMesh {
            positions: f.positions.clone(),
            colors,
            triangles: f.triangles.clone(),
            uv: f.uv.clone(),
            checker: look.checker,
            smooth_normals,
            textured: look.texture.is_some() && look.mode == ColorMode::Fabric,
            ..Default::default()
        };
        match look.mode {
            ColorMode::Fabric => {
                // Panels do not share particles, so a vertex takes any of its triangles' panel.
                let mut colors = vec![FABRIC; f.positions.len()];
                for (t, &g) in f.triangles.iter().zip(&f.groups) {
                    for &i in t {
                        colors[i as usize] = panel_color(g, &look.colors);
                    }
                }
                Ok((mesh(colors), None))
            }
            ColorMode::Strain => {
                let max = look.strain_max;
                let rest = self.rest(f.positions.len())?;
                let strain = triangle_strain(rest, &f.positions, &f.triangles);
                // Flat colours per triangle: every triangle gets its own three vertices.
                let mut m = DrawMesh {
                    checker: look.checker,
                    ..Default::default()
                };
                for (t, s) in f.triangles.iter().zip(strain) {
                    let base = m.positions.len() as u32;
                    for &i in t {
                        m.positions.push(f.positions[i as usize]);
                        m.colors.push(strain_ramp(s / max));
                        if let Some(uv) = f.uv.get(i as usize) {
                            m.uv.push(*uv);
                        }
                    }
                    m.triangles.push([base, base + 1, base + 2]);
                }
                Ok((m, Some(strain_legend(max))))
            }
            ColorMode::Penetration => {
                if self.bodies.is_empty() {
                    return Err(bad(
                        &self.run,
                        "penetration colours need a body, and the run's scene has no [body]",
                        "use --mode fabric or --mode strain",
                    ));
                }
                if self.exact.is_none() {
                    let exact = (self.bodies.iter())
                        .map(|(body, _)| ExactBody::new(&body.mesh))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|e| {
                            Error::Gpu(format!("cannot measure distances to the body: {e}"))
                        })?;
                    self.exact = Some(exact);
                }
                let t = f.number as f32 / self.fps;
                // A deforming body's exact mesh is rebuilt as it is deformed at the frame.
                for (i, d) in self.deforms.iter().enumerate() {
                    if let Some(d) = d {
                        let mesh = crate::mesh::TriMesh {
                            positions: d.positions_at(t),
                            triangles: self.bodies[i].0.mesh.triangles.clone(),
                        };
                        let e = ExactBody::new(&mesh).map_err(|e| {
                            Error::Gpu(format!("cannot measure distances to the body: {e}"))
                        })?;
                        self.exact.as_mut().expect("built above")[i] = e;
                    }
                }
                let exact = self.exact.as_ref().expect("built above");
                let poses: Vec<_> = (self.bodies.iter().zip(&self.deforms))
                    .map(|((_, s), d)| match d {
                        Some(_) => crate::body::motion::BodyState::REST,
                        None => s.motion.at(t),
                    })
                    .collect();
                // The thinnest body sets the scale; a particle's distance is to the nearest body.
                let thickness = (self.bodies.iter())
                    .map(|(_, s)| s.thickness)
                    .fold(f32::INFINITY, f32::min);
                let scale = PenetrationScale::for_thickness(thickness);
                let colors = (f.positions.iter())
                    .map(|p| {
                        let phi = (exact.iter().zip(&poses))
                            .map(|(e, pose)| {
                                e.query(pose.rotation.inverse() * (*p - pose.translation)).0
                            })
                            .fold(f32::INFINITY, f32::min);
                        scale.color(phi)
                    })
                    .collect();
                Ok((mesh(colors), Some(penetration_legend(scale))))
            }
        }
    }

    /// Normals averaged across the garment's seams, so that its shading runs smooth from
    /// panel to panel (empty for other cloth, or a frame of another mesh).
    fn smooth_normals(&mut self, f: &FrameMesh) -> Result<Vec<Vec3>, Error> {
        if self.weld.is_none() {
            let garment = match self.scene {
                Some(s) => s.build_garment()?,
                None => None,
            };
            self.weld = Some(garment.as_ref().map(crate::pattern::weld::Weld::of_garment));
        }
        let Some(Some(weld)) = &self.weld else {
            return Ok(Vec::new());
        };
        if weld.vertex_of.len() != f.positions.len() {
            return Ok(Vec::new());
        }
        let own = crate::mesh::vertex_normals(&f.positions, &f.triangles);
        let mut shared = vec![Vec3::ZERO; weld.len()];
        for (n, &v) in own.iter().zip(&weld.vertex_of) {
            shared[v as usize] += *n;
        }
        Ok(weld.vertex_of.iter().map(|&v| shared[v as usize]).collect())
    }

    /// Reads the fabric image of `setting` unless it is the one read already.
    fn load_texture(
        &mut self,
        setting: Option<&crate::scene::TextureSetting>,
    ) -> Result<(), Error> {
        match setting {
            Some(setting) if self.texture.as_ref().is_none_or(|(s, _)| s != setting) => {
                self.texture = Some((setting.clone(), FabricTexture::load(setting)?));
            }
            _ => {}
        }
        Ok(())
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

    /// Body `i`'s vertices in the world at `frame`: posed rigidly, or deformed.
    fn body_positions(&self, i: usize, frame: u32) -> Vec<Vec3> {
        let t = frame as f32 / self.fps;
        match &self.deforms[i] {
            Some(d) => d.positions_at(t),
            None => {
                let (body, settings) = &self.bodies[i];
                let pose = settings.motion.at(t);
                (body.mesh.positions.iter())
                    .map(|p| pose.rotation * *p + pose.translation)
                    .collect()
            }
        }
    }

    /// The box a preset camera frames: the cloth, and the bodies where they lie near the
    /// cloth's box (a T-shirt's head, a skirt's hips, not the whole mannequin).
    pub fn framing_box(&self, frame: u32, cloth: &[Vec3]) -> (Vec3, Vec3) {
        let (lo, hi) = bounds(cloth.iter().copied());
        // Up by 40% of the cloth's height (a T-shirt's head), elsewhere by 10% of its size.
        let side = Vec3::splat(0.1 * (hi - lo).max_element());
        let (near_lo, near_hi) = (lo - side, hi + side + Vec3::Y * 0.4 * (hi.y - lo.y));
        let near: Vec<Vec3> = (0..self.bodies.len())
            .flat_map(|i| self.body_positions(i, frame))
            .filter(|p| p.cmpge(near_lo).all() && p.cmple(near_hi).all())
            .collect();
        if near.is_empty() {
            return (lo, hi);
        }
        let (b_lo, b_hi) = bounds(near.into_iter());
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
        let f = self.load(n)?;
        let (frame, positions) = (f.number, &f.positions);
        let (cloth, legend) = self.cloth(&f, look)?;
        let (w, h) = look.size;
        let (lo, hi) = framing.unwrap_or_else(|| self.framing_box(frame, positions));
        let camera = look.camera.camera(lo, hi, w as f32 / h as f32);
        let mut meshes = vec![cloth];
        if look.seams {
            let segments = self.seam_segments()?.to_vec();
            let width_px = (h as f32 / 400.0).max(2.0);
            meshes.push(seam_ribbons(positions, &segments, &camera, h, width_px));
        }
        for (i, (body, _)) in self.bodies.iter().enumerate() {
            meshes.push(DrawMesh {
                positions: self.body_positions(i, frame),
                colors: vec![BODY; body.mesh.positions.len()],
                triangles: body.mesh.triangles.clone(),
                closed: true,
                ..Default::default()
            });
        }
        if look.occlusion {
            // The cloth and the bodies shade each other; the seam ribbons take no part.
            let solid: Vec<usize> = (0..meshes.len())
                .filter(|&k| !(look.seams && k == 1))
                .collect();
            let fits = |o: &Vec<Vec<[f32; 2]>>| {
                o.len() == solid.len()
                    && (o.iter().zip(&solid)).all(|(v, &k)| v.len() == meshes[k].positions.len())
            };
            let cached = (self.occlusion.take()).filter(|(n, o)| *n == frame && fits(o));
            let open = match cached {
                Some((_, open)) => open,
                None => {
                    let picked: Vec<DrawMesh> = solid.iter().map(|&k| meshes[k].clone()).collect();
                    ambient_occlusion(&picked)
                }
            };
            for (&k, o) in solid.iter().zip(&open) {
                meshes[k].occlusion = o.clone();
            }
            self.occlusion = Some((frame, open));
        }
        self.load_texture(look.texture.as_ref())?;
        let texture = (self.texture.as_ref())
            .filter(|_| look.texture.is_some())
            .map(|(_, t)| t);
        let mut pixels = render_textured(&self.ctx, &meshes, texture, &camera, w, h)?;
        if let Some(legend) = legend.filter(|_| look.legend) {
            draw_legend(&mut pixels, w, h, &legend);
        }
        Ok(pixels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn pattern_coordinates_turn_so_that_u_runs_along_each_panels_warp() {
        // Two panels of one triangle each: "front" cut on the bias (45°), "back" on the
        // default grain (10°); the third vertex of each lies along its panel's warp.
        let warp = |deg: f32| Vec2::from_angle(deg.to_radians());
        let frame = FrameMesh {
            positions: vec![Vec3::ZERO; 6],
            triangles: vec![[0, 1, 2], [3, 4, 5]],
            groups: vec![0, 1],
            group_names: vec!["front".into(), "back".into()],
            uv: vec![
                Vec2::ZERO,
                Vec2::Y,
                0.3 * warp(45.0),
                Vec2::ZERO,
                Vec2::X,
                0.3 * warp(10.0),
            ],
            ..Default::default()
        };
        let grain = crate::scene::Grain {
            default: 10f32.to_radians(),
            panels: [("front".to_string(), 45f32.to_radians())].into(),
        };
        let uv = along_grain(&frame, &grain);
        // A rotation of f32 unit vectors: a few ulps of 0.3 m.
        for (got, want) in [
            (uv[2], Vec2::new(0.3, 0.0)),
            (uv[5], Vec2::new(0.3, 0.0)),
            // The panel's y axis, turned by −45° with the rest of the front.
            (uv[1], Vec2::splat(0.5f32.sqrt())),
        ] {
            assert!(got.distance(want) < 1e-6, "{got} against {want}");
        }
        assert!(uv[3].length() == 0.0 && (uv[4].length() - 1.0).abs() < 1e-6);
    }
}
