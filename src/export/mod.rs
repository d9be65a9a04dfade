//! What a run writes of its frames: an OBJ per written frame (smooth normals, a group per
//! panel), the body beside them, a PC2 point cache and an animated glTF binary. The last two
//! need every written frame, so they are kept in memory and written at the end.

pub mod disk;
pub mod glb;
pub mod obj;
pub mod pc2;

use crate::atomic_file::write_atomic;
use crate::body::Collider;
use crate::error::Error;
use crate::scene::OutputSettings;
use crate::sim::Prepared;
use glam::{Vec2, Vec3, Vec4};
use obj::Group;
use std::path::{Path, PathBuf};

/// The point cache's file name.
pub const PC2_FILE: &str = "cloth.pc2";
/// The glTF binary's file name.
pub const GLB_FILE: &str = "garment.glb";
/// The rest-pose OBJ beside the point cache: the first written frame, in particle order.
pub const REST_FILE: &str = "rest.obj";

/// Writes a run's frames as they come and its caches at the end.
pub struct Exporter<'a> {
    dir: PathBuf,
    settings: OutputSettings,
    frame_dt: f32,
    triangles: &'a [[u32; 3]],
    uv: Option<&'a [Vec2]>,
    groups: Vec<Group>,
    bodies: &'a [std::sync::Arc<Collider>],
    /// The written frames' numbers and positions, kept for the PC2 and glTF files.
    kept_frames: Vec<u32>,
    kept: Vec<Vec<Vec3>>,
    written: usize,
}

impl<'a> Exporter<'a> {
    /// An exporter of `prep`'s cloth and body into `dir`, as `output` asks.
    pub fn new(prep: &'a Prepared, output: &OutputSettings, dir: &Path) -> Self {
        let triangles = &prep.model.triangles[..];
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
            for (i, c) in self.bodies.iter().enumerate() {
                let stem = self.body_name(i);
                let name = if c.motion.moves() {
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

    /// Writes the point cache and the glTF binary of the frames seen so far (also after a run
    /// that stopped early) and returns their names.
    pub fn finish(&self) -> Result<Vec<String>, Error> {
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
        if self.settings.gltf {
            let times: Vec<f32> = (self.kept_frames.iter())
                .map(|&f| f as f32 * self.frame_dt)
                .collect();
            let cloth = glb::ClothTrack {
                triangles: self.triangles,
                uv: self.uv,
                times: &times,
                frames: &self.kept,
            };
            let bodies: Vec<glb::BodyTrack> = (self.bodies.iter().enumerate())
                .map(|(i, c)| glb::BodyTrack {
                    name: self.body_name(i),
                    positions: &c.body.mesh.positions,
                    triangles: &c.body.mesh.triangles,
                    poses: if c.motion.moves() {
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
                .collect();
            let bytes = glb::glb_bytes(&cloth, &bodies).ok_or_else(|| self.too_large(GLB_FILE))?;
            self.write(GLB_FILE, &bytes)?;
            names.push(GLB_FILE.to_string());
        }
        Ok(names)
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

    /// The body's vertices in world coordinates at `frame`'s time.
    fn body_world(&self, c: &Collider, frame: u32) -> Vec<Vec3> {
        let pose = c.motion.at(frame as f32 * self.frame_dt);
        (c.body.mesh.positions.iter())
            .map(|p| pose.rotation * *p + pose.translation)
            .collect()
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
