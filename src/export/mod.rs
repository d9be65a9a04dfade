//! What a run writes of its frames: an OBJ per written frame (smooth normals, a group per
//! panel) and the body beside them.

pub mod obj;

use crate::atomic_file::write_atomic;
use crate::body::Collider;
use crate::error::Error;
use crate::scene::OutputSettings;
use crate::sim::Prepared;
use glam::{Vec2, Vec3, Vec4};
use obj::Group;
use std::path::{Path, PathBuf};

/// Writes a run's frames as they come.
pub struct Exporter<'a> {
    dir: PathBuf,
    settings: OutputSettings,
    frame_dt: f32,
    triangles: &'a [[u32; 3]],
    uv: Option<&'a [Vec2]>,
    groups: Vec<Group>,
    body: Option<&'a Collider>,
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
            body: prep.model.collider.as_deref(),
            written: 0,
        }
    }

    /// Whether any file is written per frame (if not, no frame needs reading back).
    pub fn wants_frames(&self) -> bool {
        self.settings.obj
    }

    /// Whether `frame` is on the `every` schedule.
    pub fn on_schedule(&self, frame: u32) -> bool {
        frame.is_multiple_of(self.settings.every)
    }

    /// Writes one frame and returns the names of the files written.
    pub fn frame(&mut self, frame: u32, positions: &[Vec4]) -> Result<Vec<String>, Error> {
        let positions: Vec<Vec3> = positions.iter().map(|p| p.truncate()).collect();
        let mut names = Vec::new();
        if self.settings.obj {
            let name = format!("frame_{frame:04}.obj");
            let text = obj::cloth_obj(&positions, self.triangles, self.uv, &self.groups);
            self.write(&name, text.as_bytes())?;
            names.push(name);
            if let Some(c) = self.body {
                let name = if c.motion.moves() {
                    Some(format!("body_{frame:04}.obj"))
                } else {
                    (self.written == 0).then(|| "body.obj".to_string())
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
        self.written += 1;
        Ok(names)
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
}
