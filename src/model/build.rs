//! Building the cloth model from a validated scene: mesh or pattern, pins, attachments, seams,
//! hinges across seams, and the collision body.

use super::collider::build_collider;
use super::layout::{Hinge, Seam};
use super::ClothModel;
use crate::error::InputError;
use crate::mesh::TriMesh;
use crate::pattern::garment::Garment;
use crate::pattern::Pattern;
use crate::scene::{ClothSource, Corner, GridEdge, PinSelection, Scene};
use glam::Vec3;

/// What `Scene::build_model` makes.
pub struct BuiltCloth {
    /// The model, attached particles pinned.
    pub model: ClothModel,
    /// The sewn pattern, for `[cloth.pattern]` scenes.
    pub garment: Option<Garment>,
    /// Particles the scene's `[[pins]]` hold for the whole run.
    pub scene_pins: Vec<u32>,
    /// Particles held by `attach_labels` until they are released.
    pub attached: Vec<u32>,
}

impl Scene {
    /// The cloth's triangle mesh in metres.
    pub fn build_mesh(&self) -> Result<TriMesh, InputError> {
        match &self.cloth {
            ClothSource::Grid {
                width,
                height,
                columns,
                rows,
                center,
                plane,
            } => Ok(TriMesh::grid(
                *width, *height, *columns, *rows, *center, *plane,
            )),
            ClothSource::Mesh {
                path,
                scale,
                offset,
            } => {
                let mut mesh = TriMesh::load_obj(path, *scale, "cloth.mesh.path").map_err(|e| {
                    self.error(
                        "cloth.mesh",
                        "path",
                        format!("{}: {}", path.display(), e.problem),
                        e.fix,
                    )
                })?;
                for p in &mut mesh.positions {
                    *p += *offset;
                }
                Ok(mesh)
            }
            ClothSource::Pattern { .. } => Ok(self.build_garment()?.expect("a pattern").mesh),
        }
    }

    /// Refuses a cloth in which no particle can move: one without mass (its triangles have no
    /// area: a degenerate mesh, or a pattern whose units shrink it to a point), or one whose
    /// every particle with mass is among `pins` (the scene's; particles held by
    /// `attach_labels` are let go later).
    fn something_moves(&self, model: &ClothModel, pins: &[u32]) -> Result<(), InputError> {
        let mut pinned = vec![false; model.len()];
        for &p in pins {
            pinned[p as usize] = true;
        }
        if (model.masses.iter().zip(&pinned)).any(|(&m, &p)| !p && m > 0.0) {
            return Ok(());
        }
        if model.masses.iter().all(|&m| m <= 0.0) {
            let (table, key) = match &self.cloth {
                ClothSource::Mesh { .. } => ("cloth.mesh", "path"),
                ClothSource::Pattern { .. } => ("cloth.pattern", "path"),
                _ => ("cloth.grid", "width_m"),
            };
            return Err(self.error(
                table,
                key,
                format!(
                    "its {} triangle(s) have no area (every one has its corners on a line), so \
                     the cloth has no mass",
                    model.triangles.len()
                ),
                "give the cloth triangles of real area (check the mesh, or the pattern's units)",
            ));
        }
        Err(self.error(
            "pins",
            "",
            format!("all {} particles are pinned: nothing can move", model.len()),
            "pin fewer particles",
        ))
    }

    /// The particles held by `attach_labels` for the first `attach_frames` frames.
    pub fn attached_particles(&self, garment: &Garment) -> Result<Vec<u32>, InputError> {
        let ClothSource::Pattern {
            attach_labels,
            attach_frames,
            ..
        } = &self.cloth
        else {
            return Ok(Vec::new());
        };
        if attach_labels.is_empty() || *attach_frames == 0 {
            return Ok(Vec::new());
        }
        let ids = garment.particles_on_labelled_edges(attach_labels);
        if ids.is_empty() {
            let mut found: Vec<&String> = garment.edge_labels.iter().flatten().flatten().collect();
            found.sort();
            found.dedup();
            return Err(self.error(
                "cloth.pattern",
                "attach_labels",
                format!("no edge of the pattern has a label in {attach_labels:?}"),
                format!("use labels the pattern has: {found:?}"),
            ));
        }
        Ok(ids)
    }

    /// The sewn cloth of a `[cloth.pattern]` scene (`None` for grids and meshes), within the
    /// memory cap (see `build_garment_within`).
    pub fn build_garment(&self) -> Result<Option<Garment>, InputError> {
        let room = super::budget::check_budget(self)?;
        self.build_garment_within(room)
    }

    /// The sewn cloth with at most `max_particles` particles: the mesher stops there.
    fn build_garment_within(&self, max_particles: usize) -> Result<Option<Garment>, InputError> {
        let ClothSource::Pattern { path, options, .. } = &self.cloth else {
            return Ok(None);
        };
        let pattern = Pattern::load(path)?;
        Ok(Some(Garment::build_within(
            &pattern,
            options,
            max_particles,
        )?))
    }

    /// Each triangle's warp direction: the pattern's panel axes (or the grid's width, or world
    /// x for a mesh) turned by the scene's grain angles.
    fn grain_directions(
        &self,
        mesh: &TriMesh,
        garment: Option<&Garment>,
    ) -> Result<Vec<Vec3>, InputError> {
        let g = &self.grain;
        let Some(garment) = garment else {
            if let Some(name) = g.panels.keys().next() {
                return Err(self.error(
                    "fabric.panel_grain_deg",
                    name,
                    "the cloth has no panels (it is not a sewing pattern)",
                    "use [fabric] grain_deg for a grid or a mesh",
                ));
            }
            let normal = match &self.cloth {
                ClothSource::Grid {
                    plane: crate::mesh::GridPlane::Xz,
                    ..
                } => Vec3::Y,
                _ => Vec3::Z,
            };
            let n = mesh.triangles.len();
            return Ok(super::membrane::world_grain(n, g.default, normal));
        };
        let mut by_panel = vec![g.default; garment.panel_names.len()];
        for (name, &angle) in &g.panels {
            let Some(k) = garment.panel_names.iter().position(|p| p == name) else {
                return Err(self.error(
                    "fabric.panel_grain_deg",
                    name,
                    format!("the pattern has no panel {name:?}"),
                    format!("use one of {:?}", garment.panel_names),
                ));
            };
            by_panel[k] = angle;
        }
        let panel = &garment.triangle_panel;
        Ok(super::membrane::chart_grain(
            &mesh.positions,
            &garment.uv,
            &mesh.triangles,
            |t| by_panel[panel[t] as usize],
        ))
    }

    /// The particles each pin entry selects; an entry that selects nothing is an error.
    pub fn pinned_particles(&self, mesh: &TriMesh) -> Result<Vec<u32>, InputError> {
        let c = self.checker();
        let n = mesh.positions.len() as u32;
        let mut all = Vec::new();
        for (k, pin) in self.pins.iter().enumerate() {
            let table = format!("pins[{k}]");
            let ids: Vec<u32> = match (pin, &self.cloth) {
                (PinSelection::Corners(cs), ClothSource::Grid { columns, rows, .. }) => cs
                    .iter()
                    .map(|corner| match corner {
                        Corner::TopLeft => (rows - 1) * columns,
                        Corner::TopRight => rows * columns - 1,
                        Corner::BottomLeft => 0,
                        Corner::BottomRight => columns - 1,
                    })
                    .collect(),
                (PinSelection::Edge(e), ClothSource::Grid { columns, rows, .. }) => match e {
                    GridEdge::Top => ((rows - 1) * columns..rows * columns).collect(),
                    GridEdge::Bottom => (0..*columns).collect(),
                    GridEdge::Left => (0..*rows).map(|r| r * columns).collect(),
                    GridEdge::Right => (0..*rows).map(|r| r * columns + columns - 1).collect(),
                },
                (PinSelection::Indices(ids), _) => {
                    if let Some(&bad) = ids.iter().find(|&&i| i >= n) {
                        return Err(c.err(
                            &table,
                            "indices",
                            format!("particle {bad} does not exist; the cloth has {n} particles"),
                            format!("use indices from 0 to {}", n - 1),
                        ));
                    }
                    ids.clone()
                }
                (PinSelection::Box { min, max }, _) => (0..n)
                    .filter(|&i| {
                        let p = mesh.positions[i as usize];
                        p.cmpge(*min).all() && p.cmple(*max).all()
                    })
                    .collect(),
                _ => unreachable!("named corners and edges are refused for meshes at load time"),
            };
            if ids.is_empty() {
                let (lo, hi) = mesh.positions.iter().fold(
                    (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                    |(lo, hi), p| (lo.min(*p), hi.max(*p)),
                );
                return Err(c.err(
                    &table,
                    "",
                    "selects no particle",
                    format!("the cloth spans {lo:?} to {hi:?} m; widen the selection"),
                ));
            }
            all.extend(ids);
        }
        all.sort_unstable();
        all.dedup();
        Ok(all)
    }

    /// Builds the cloth model (mesh, fabric, pins and seams) and, for patterns, the garment.
    pub fn build_model(&self) -> Result<BuiltCloth, InputError> {
        let room = super::budget::check_budget(self)?;
        let garment = self.build_garment_within(room)?;
        let mesh = match &garment {
            Some(g) => g.mesh.clone(),
            None => self.build_mesh()?,
        };
        super::budget::check_mesh_scale(self, &mesh)?;
        let scene_pins = self.pinned_particles(&mesh)?;
        let attached = match &garment {
            Some(g) => self.attached_particles(g)?,
            None => Vec::new(),
        };
        let pinned: Vec<u32> = scene_pins.iter().chain(&attached).copied().collect();
        let mut model = ClothModel::from_mesh(&mesh, &self.fabric, &pinned);
        self.something_moves(&model, &scene_pins)?;
        let grain = match self.fabric.membrane {
            Some(_) => Some(self.grain_directions(&mesh, garment.as_ref())?),
            None => None,
        };
        for (i, b) in self.bodies.iter().enumerate() {
            let collider = build_collider(b, &self.checker(), &self.body_table(i))?;
            model.colliders.push(std::sync::Arc::new(collider));
        }
        // Each seam hinge's index and the other panel's sewn edge: it bends by both panels' grain.
        let mut seam_sides = Vec::new();
        if let (
            Some(g),
            ClothSource::Pattern {
                seam_stiffness,
                sewing_time,
                folds,
                ..
            },
        ) = (&garment, &self.cloth)
        {
            let c = self.checker();
            let mut fold_of = vec![0.0f32; g.stitches];
            for (k, &(stitch, angle)) in folds.iter().enumerate() {
                if stitch >= g.stitches {
                    return Err(c.err(
                        &format!("cloth.pattern.seams[{k}]"),
                        "stitch",
                        format!(
                            "the pattern has {} stitches; there is no stitch {stitch}",
                            g.stitches
                        ),
                        format!("use a stitch index from 0 to {}", g.stitches.max(1) - 1),
                    ));
                }
                fold_of[stitch] = angle;
            }
            // Hinges across seams bend like the fabric and rest at the seam's fold angle. The
            // panels lie apart until sewn, so the rest weight takes the first panel's triangle
            // for both sides (the mesh spacing is the same on both).
            if let Some(kb) = self.fabric.bending_stiffness {
                let first = model.hinges.len();
                seam_sides.extend(
                    (g.seam_hinges.iter().enumerate()).map(|(k, h)| (first + k, h.other_edge)),
                );
                model.hinges.extend(g.seam_hinges.iter().map(|h| {
                    let p = |i: u32| model.positions[i as usize];
                    let [x3, x4, x1] = [h.v[0], h.v[1], h.v[2]].map(p);
                    let n1 = (x1 - x3).cross(x1 - x4).length();
                    Hinge {
                        v: h.v,
                        stiffness: kb,
                        rest_sin_half: (0.5 * fold_of[h.stitch as usize]).sin(),
                        rest_weight: if n1 > 0.0 {
                            kb * (x4 - x3).length_squared() / (2.0 * n1)
                        } else {
                            0.0
                        },
                        _pad1: 0,
                    }
                }));
            }
            model.seams = g
                .seam_pairs
                .iter()
                .map(|p| {
                    let m = |i: u32| model.masses[i as usize];
                    let partner_mass = (1.0 - p.w) * m(p.b[0]) + p.w * m(p.b[1]);
                    let reduced = m(p.a) * partner_mass / (m(p.a) + partner_mass);
                    let x = |i: u32| model.positions[i as usize];
                    let partner = x(p.b[0]).lerp(x(p.b[1]), p.w);
                    Seam {
                        v: [p.a, p.b[0], p.b[1], 0],
                        weight: p.w,
                        stiffness: *seam_stiffness,
                        damping: 2.0
                            * self.fabric.damping_ratio
                            * (*seam_stiffness * reduced).sqrt(),
                        // With a sewing time the pair starts at rest where it was placed.
                        open_gap: if *sewing_time > 0.0 {
                            x(p.a).distance(partner)
                        } else {
                            0.0
                        },
                    }
                })
                .collect();
        }
        // After the seams' hinges, which bend by direction too.
        if let Some(grain) = grain {
            model.set_grain(&grain, &self.fabric, &seam_sides);
        }
        model.multigrid = self
            .build_multigrid(&model, garment.as_ref())
            .map(std::sync::Arc::new);
        Ok(BuiltCloth {
            model,
            garment,
            scene_pins,
            attached,
        })
    }
}
