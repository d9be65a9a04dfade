//! What a run writes of its frames: an OBJ per written frame (smooth normals, a group per
//! panel), the bodies beside them (one mesh each; a moving body's motion as a node animation in
//! `body.glb`), a PC2 point cache and an animated glTF binary (a sewn garment welded into one
//! mesh). The caches need every written frame, so they are kept in memory and written at the
//! end.

pub mod disk;
pub mod glb;
pub mod obj;
pub mod pc2;

use crate::atomic_file::write_atomic;
use crate::body::Collider;
use crate::error::Error;
use crate::pattern::garment::Garment;
use crate::scene::{OutputSettings, Scene, TextureSetting};
use crate::sim::Prepared;
use glam::{Quat, Vec2, Vec3, Vec4};
use obj::Group;
use std::path::{Path, PathBuf};

/// The point cache's file name.
pub const PC2_FILE: &str = "cloth.pc2";
/// The glTF binary's file name.
pub const GLB_FILE: &str = "garment.glb";
/// The rest-pose OBJ beside the point cache: the first written frame, in particle order.
pub const REST_FILE: &str = "rest.obj";
/// The moving bodies' glTF binary: each body's mesh once, its motion as a node animation.
pub const BODY_GLB_FILE: &str = "body.glb";

/// Writes a run's frames as they come and its caches at the end.
pub struct Exporter<'a> {
    dir: PathBuf,
    settings: OutputSettings,
    frame_dt: f32,
    triangles: &'a [[u32; 3]],
    uv: Option<&'a [Vec2]>,
    groups: Vec<Group>,
    bodies: &'a [std::sync::Arc<Collider>],
    garment: Option<&'a Garment>,
    seam_closed_gap: f32,
    /// The glTF's materials, one per panel (one for other cloth).
    materials: Vec<glb::ClothMaterial>,
    texture: Option<TextureSetting>,
    /// What the glTF binary could not do as asked (weld a garment whose seams stayed open).
    pub warnings: Vec<String>,
    /// The written frames' numbers and positions, kept for the PC2 and glTF files.
    kept_frames: Vec<u32>,
    kept: Vec<Vec<Vec3>>,
    written: usize,
}

impl<'a> Exporter<'a> {
    /// An exporter of `prep`'s cloth and body into `dir`, as `scene`'s `[output]` asks, in
    /// its preview colours.
    pub fn new(prep: &'a Prepared, scene: &Scene, dir: &Path) -> Self {
        let output = &scene.output;
        let triangles = &prep.model.triangles[..];
        let color = |k: usize| match scene.preview.colors.len() {
            0 => crate::preview::fabric_color(&scene.fabric),
            n => scene.preview.colors[k % n],
        };
        let materials = match &prep.garment {
            Some(g) => (g.panel_names.iter().enumerate())
                .map(|(k, name)| glb::ClothMaterial {
                    name: name.clone(),
                    color: color(k),
                })
                .collect(),
            None => vec![glb::ClothMaterial {
                name: "fabric".into(),
                color: color(0),
            }],
        };
        let groups = match &prep.garment {
            Some(g) => obj::panel_groups(&g.panel_names, &g.triangle_panel),
            None => vec![Group {
                name: "cloth".into(),
                triangles: (0..triangles.len() as u32).collect(),
            }],
        };
        Exporter {
            dir: dir.to_path_buf(),
            settings: output.clone(),
            frame_dt: prep.frame_dt,
            triangles,
            uv: prep.garment.as_ref().map(|g| &g.uv[..]),
            groups,
            bodies: &prep.model.colliders,
            garment: prep.garment.as_ref(),
            seam_closed_gap: prep.seam_closed_gap,
            materials,
            texture: scene.preview.texture.clone(),
            warnings: Vec::new(),
            kept_frames: Vec::new(),
            kept: Vec::new(),
            written: 0,
        }
    }

    /// Whether any file is written per frame (if not, no frame needs reading back).
    pub fn wants_frames(&self) -> bool {
        self.settings.obj || self.settings.pc2 || self.settings.gltf
    }

    /// Whether `frame` is on the `every` schedule.
    pub fn on_schedule(&self, frame: u32) -> bool {
        frame.is_multiple_of(self.settings.every)
    }

    /// Writes (or keeps) one frame and returns the names of the files written.
    pub fn frame(&mut self, frame: u32, positions: &[Vec4]) -> Result<Vec<String>, Error> {
        let positions: Vec<Vec3> = positions.iter().map(|p| p.truncate()).collect();
        let mut names = Vec::new();
        if self.settings.obj {
            let name = format!("frame_{frame:04}.obj");
            let text = obj::cloth_obj(&positions, self.triangles, self.uv, &self.groups);
            self.write(&name, text.as_bytes())?;
            names.push(name);
            // A rigid body once, at the first written frame's pose: a moving one's motion is
            // body.glb's node animation. A deforming body at every frame: no node animation
            // holds its shape.
            for (i, c) in self.bodies.iter().enumerate() {
                let stem = self.body_name(i);
                let name = if c.deformed.is_some() {
                    Some(format!("{stem}_{frame:04}.obj"))
                } else {
                    (self.written == 0).then(|| format!("{stem}.obj"))
                };
                if let Some(name) = name {
                    let world = self.body_world(c, frame);
                    self.write(
                        &name,
                        obj::body_obj(&world, &c.body.mesh.triangles).as_bytes(),
                    )?;
                    names.push(name);
                }
            }
        }
        if self.settings.pc2 && self.written == 0 {
            // A PC2 file holds only points: DCC tools apply it to a mesh with the same vertex
            // order, which this is (also when no OBJ frames are written).
            let text = obj::cloth_obj(&positions, self.triangles, self.uv, &self.groups);
            self.write(REST_FILE, text.as_bytes())?;
            names.push(REST_FILE.to_string());
        }
        if self.settings.pc2 || self.settings.gltf {
            self.kept_frames.push(frame);
            self.kept.push(positions);
        }
        self.written += 1;
        Ok(names)
    }

    /// Writes `positions` as `frame_0000.obj` only (no body, not kept for the caches): the rest
    /// shape of a run that starts later, from a coarse start. Returns the file's name.
    pub fn rest_frame(&self, positions: &[Vec3]) -> Result<Vec<String>, Error> {
        if !self.settings.obj {
            return Ok(Vec::new());
        }
        let name = "frame_0000.obj".to_string();
        let text = obj::cloth_obj(positions, self.triangles, self.uv, &self.groups);
        self.write(&name, text.as_bytes())?;
        Ok(vec![name])
    }

    /// Writes the point cache and the glTF binaries of the frames seen so far (also after a
    /// run that stopped early) and returns their names.
    pub fn finish(&mut self) -> Result<Vec<String>, Error> {
        let mut names = Vec::new();
        if self.kept.is_empty() {
            return Ok(names);
        }
        if self.settings.pc2 {
            // Samples are `every` frames apart from the first; a last frame written between
            // them (the settle rule) takes the next slot.
            let start = self.kept_frames[0] as f32;
            let bytes = pc2::pc2_bytes(&self.kept, start, self.settings.every as f32)
                .ok_or_else(|| self.too_large(PC2_FILE))?;
            self.write(PC2_FILE, &bytes)?;
            names.push(PC2_FILE.to_string());
        }
        let times: Vec<f32> = (self.kept_frames.iter())
            .map(|&f| f as f32 * self.frame_dt)
            .collect();
        if self.bodies.iter().any(|c| c.motion.moves()) {
            let bodies = self.body_tracks(&times);
            let bytes = glb::glb_bytes(None, &bodies, &times)
                .ok_or_else(|| self.too_large(BODY_GLB_FILE))?;
            self.write(BODY_GLB_FILE, &bytes)?;
            names.push(BODY_GLB_FILE.to_string());
        }
        if self.settings.gltf {
            let bytes = self.garment_glb(&times)?;
            self.write(GLB_FILE, &bytes)?;
            names.push(GLB_FILE.to_string());
        }
        Ok(names)
    }

    /// Which kept frames the glTF binary starts from, and whether it welds the garment. A sewn
    /// garment starts at the first frame with every seam closed (the seams' drawing-together
    /// in zero gravity is how the garment is built, not how it moves), welded when
    /// `weld_seams`; one whose seams never closed starts at its first simulated frame, unwelded,
    /// with a warning. Other cloth starts at its first frame.
    fn gltf_start(&mut self) -> (usize, bool) {
        let Some(g) = self.garment else {
            return (0, false);
        };
        let closed = |frame: &Vec<Vec3>| {
            let p: Vec<Vec4> = frame.iter().map(|v| v.extend(0.0)).collect();
            let gaps = crate::metrics::seam_gaps(&g.seam_pairs, g.stitches, &p);
            gaps.iter().all(|&gap| gap < self.seam_closed_gap)
        };
        if let Some(k) = self.kept.iter().position(closed) {
            return (k, self.settings.weld_seams);
        }
        if self.settings.weld_seams && g.stitches > 0 {
            self.warnings.push(format!(
                "{GLB_FILE} is not welded: the garment's seams never all closed, so it holds the \
                 separate panels from the first simulated frame on"
            ));
        }
        let simulated = self.kept_frames.iter().position(|&f| f > 0);
        (simulated.unwrap_or(0), false)
    }

    /// The glTF binary of the kept frames from `gltf_start` on, with the bodies.
    fn garment_glb(&mut self, all_times: &[f32]) -> Result<Vec<u8>, Error> {
        let (start, weld) = self.gltf_start();
        let times = &all_times[start..];
        let frames = &self.kept[start..];
        let welded = weld
            .then(|| crate::pattern::weld::Weld::of_garment(self.garment.expect("weld needs one")));
        let (frames, triangles, uv) = match &welded {
            Some(w) => (
                frames.iter().map(|f| w.positions(f)).collect(),
                w.triangles.clone(),
                self.uv.map(|uv| w.uv(uv)),
            ),
            None => (
                frames.to_vec(),
                self.triangles.to_vec(),
                self.uv.map(<[Vec2]>::to_vec),
            ),
        };
        let texture = match &self.texture {
            Some(t) => Some(glb::FabricImage {
                png: std::fs::read(&t.path).map_err(|e| Error::io(&t.path, e))?,
                size_m: t.size_m,
            }),
            None => None,
        };
        let cloth = glb::ClothTrack {
            triangles: &triangles,
            uv: uv.as_deref(),
            times,
            frames: &frames,
            materials: &self.materials,
            triangle_material: self.garment.map(|g| &g.triangle_panel[..]),
            texture: texture.as_ref(),
        };
        let bodies = self.body_tracks(times);
        glb::glb_bytes(Some(&cloth), &bodies, times).ok_or_else(|| self.too_large(GLB_FILE))
    }

    /// Every body's mesh and its poses at `times` (one pose when it never moves); a deforming
    /// body's world positions at `times` instead, at the identity pose.
    fn body_tracks(&self, times: &[f32]) -> Vec<glb::BodyTrack<'a>> {
        (self.bodies.iter().enumerate())
            .map(|(i, c)| glb::BodyTrack {
                name: self.body_name(i),
                positions: &c.body.mesh.positions,
                triangles: &c.body.mesh.triangles,
                frames: match c.deformed {
                    Some(_) => times.iter().map(|&t| c.world_positions(t)).collect(),
                    None => Vec::new(),
                },
                poses: if c.deformed.is_some() {
                    vec![(Quat::IDENTITY, Vec3::ZERO)]
                } else if c.motion.moves() {
                    let pose = |t: f32| c.motion.at(t);
                    times
                        .iter()
                        .map(|&t| (pose(t).rotation, pose(t).translation))
                        .collect()
                } else {
                    let still = c.motion.at(0.0);
                    vec![(still.rotation, still.translation)]
                },
            })
            .collect()
    }

    /// The frames kept for the caches and how many frames were written: what a checkpoint
    /// saves so that a resumed run's caches hold every frame.
    pub fn progress(&self) -> (&[u32], &[Vec<Vec3>], usize) {
        (&self.kept_frames, &self.kept, self.written)
    }

    /// Continues from a checkpoint's `progress`.
    pub fn restore(&mut self, kept_frames: Vec<u32>, kept: Vec<Vec<Vec3>>, written: usize) {
        self.kept_frames = kept_frames;
        self.kept = kept;
        self.written = written;
    }

    /// Body `i`'s file and node name: `body`, or `body0`, `body1`, … among several.
    fn body_name(&self, i: usize) -> String {
        if self.bodies.len() == 1 {
            "body".into()
        } else {
            format!("body{i}")
        }
    }

    /// The body's vertices in world coordinates at `frame`'s time (deformed, if it deforms).
    fn body_world(&self, c: &Collider, frame: u32) -> Vec<Vec3> {
        c.world_positions(frame as f32 * self.frame_dt)
    }

    fn write(&self, name: &str, bytes: &[u8]) -> Result<(), Error> {
        write_atomic(&self.dir.join(name), bytes)
    }

    /// The only way the encoders refuse consistent frames: counts past their 32-bit fields.
    fn too_large(&self, name: &str) -> Error {
        Error::io(
            &self.dir.join(name),
            std::io::Error::other("the run is too large for the format's 32-bit sizes"),
        )
    }
}
