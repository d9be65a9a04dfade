//! The `[cloth]` table: a generated grid, an OBJ mesh or a GarmentCode sewing pattern.

use super::raw::RawCloth;
use crate::check::Checker;
use crate::error::InputError;
use crate::mesh::GridPlane;
use crate::pattern::garment::{GarmentOptions, Placement};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Where the cloth's triangles come from.
#[derive(Clone, Debug, PartialEq)]
pub enum ClothSource {
    /// A generated rectangular grid.
    Grid {
        /// Width in m (along columns).
        width: f32,
        /// Height in m (along rows).
        height: f32,
        /// Particles along the width.
        columns: u32,
        /// Particles along the height.
        rows: u32,
        /// Centre in m.
        center: Vec3,
        /// The world plane the grid lies in.
        plane: GridPlane,
    },
    /// A GarmentCode sewing pattern, sewn by seam forces.
    Pattern {
        /// Absolute or scene-relative path, resolved.
        path: PathBuf,
        /// Meshing and placement options.
        options: GarmentOptions,
        /// Particle spacing of the coarse start, in m: the run first sews and drapes the
        /// garment meshed this coarsely until it settles, then continues at `options`'
        /// spacing from there (`None`: no coarse start).
        coarse_start: Option<f64>,
        /// Seam pair stiffness in N/m.
        seam_stiffness: f32,
        /// Time over which seam rest gaps shrink from the placed gap to 0, in s; 0: seams pull
        /// with their full stiffness from the start.
        sewing_time: f32,
        /// A seam counts as closed when every pair's gap is below this, in m.
        closed_gap: f32,
        /// Fold angles θ0 in radians by stitch index (others fold to 0: flat).
        folds: Vec<(usize, f32)>,
        /// Edges with these labels are held in place for the first `attach_frames` frames.
        attach_labels: Vec<String>,
        /// Output frames during which labelled edges stay attached.
        attach_frames: u32,
    },
    /// A triangle mesh from an OBJ file.
    Mesh {
        /// Absolute or scene-relative path, resolved.
        path: PathBuf,
        /// Metres per file unit.
        scale: f32,
        /// Translation in m after scaling.
        offset: Vec3,
    },
}

/// Validates `[cloth]`; `stretch` (N/m, validated with the fabric) sets the default seam stiffness.
pub(super) fn parse(
    c: &Checker,
    base: &Path,
    raw: RawCloth,
    stretch: f64,
) -> Result<ClothSource, InputError> {
    Ok(match (raw.grid, raw.mesh, raw.pattern) {
        (Some(g), None, None) => {
            let plane = match g.plane.as_str() {
                "xy" => GridPlane::Xy,
                "xz" => GridPlane::Xz,
                other => {
                    return Err(c.err(
                        "cloth.grid",
                        "plane",
                        format!("unknown plane {other:?}"),
                        "use \"xy\" (hanging) or \"xz\" (lying flat)",
                    ))
                }
            };
            ClothSource::Grid {
                width: c.positive("cloth.grid", "width_m", g.width_m, "m")?,
                height: c.positive("cloth.grid", "height_m", g.height_m, "m")?,
                columns: c.count("cloth.grid", "columns", g.columns as i64, 2)?,
                rows: c.count("cloth.grid", "rows", g.rows as i64, 2)?,
                center: c.vec3("cloth.grid", "center_m", g.center_m)?,
                plane,
            }
        }
        (None, Some(m), None) => ClothSource::Mesh {
            path: base.join(&m.path),
            scale: c.units("cloth.mesh", "units", &m.units)?,
            offset: c.vec3("cloth.mesh", "offset_m", m.offset_m)?,
        },
        (None, None, Some(p)) => {
            let t = "cloth.pattern";
            let mut placement = std::collections::HashMap::new();
            for (name, pl) in &p.placement {
                let table = format!("cloth.pattern.placement.{name}");
                placement.insert(
                    name.clone(),
                    Placement {
                        translation: c.vec3(&table, "translation", pl.translation)?.as_dvec3(),
                        rotation_deg: c.vec3(&table, "rotation_deg", pl.rotation_deg)?.as_dvec3(),
                    },
                );
            }
            let coarse_start = match p.coarse_start_distance_m {
                None => None,
                Some(given) => {
                    let d = c.within(t, "coarse_start_distance_m", given, (1e-3, 0.5), "m")?;
                    if given <= p.particle_distance_m {
                        return Err(c.err(
                            t,
                            "coarse_start_distance_m",
                            format!(
                                "the coarse start's spacing {given} m is not coarser than \
                                 particle_distance_m = {} m",
                                p.particle_distance_m
                            ),
                            "give a larger spacing (such as 4× particle_distance_m), or remove \
                             coarse_start_distance_m",
                        ));
                    }
                    Some(d as f64)
                }
            };
            ClothSource::Pattern {
                path: base.join(&p.path),
                coarse_start,
                options: GarmentOptions {
                    // Below 1 mm a garment has tens of millions of particles; above 0.5 m
                    // no panel has an interior.
                    particle_distance: c.within(
                        t,
                        "particle_distance_m",
                        p.particle_distance_m,
                        (1e-3, 0.5),
                        "m",
                    )? as f64,
                    placement,
                },
                seam_stiffness: match p.seam_stiffness_n_m {
                    Some(k) => c.positive(t, "seam_stiffness_n_m", k, "N/m")?,
                    // Twice the fabric's stretch stiffness (validated with the fabric).
                    None => (2.0 * stretch) as f32,
                },
                sewing_time: match p.seam_sewing_time_s {
                    Some(v) => c.positive(t, "seam_sewing_time_s", v, "s")?,
                    None => 0.0,
                },
                // Past a centimetre, open seams would count as sewn (and be welded shut in
                // the glTF export).
                closed_gap: c.within(
                    t,
                    "seam_closed_gap_m",
                    p.seam_closed_gap_m,
                    (1e-6, 0.01),
                    "m",
                )?,
                folds: {
                    let mut folds = Vec::new();
                    for (k, seam) in p.seams.iter().enumerate() {
                        let table = format!("cloth.pattern.seams[{k}]");
                        let stitch = c.count(&table, "stitch", seam.stitch, 0)? as usize;
                        if let Some(j) = p.seams[..k].iter().position(|s| s.stitch == seam.stitch) {
                            return Err(c.err(
                                &table,
                                "stitch",
                                format!("stitch {stitch} is given a fold already, in seams[{j}]"),
                                "give each stitch one [[cloth.pattern.seams]] entry",
                            ));
                        }
                        let fold = c.finite(&table, "fold_deg", seam.fold_deg)?;
                        if fold.abs() >= 180.0 {
                            return Err(c.err(
                                &table,
                                "fold_deg",
                                format!("{fold}° folds the panels through each other"),
                                "use an angle above -180 and below 180 degrees",
                            ));
                        }
                        folds.push((stitch, fold.to_radians()));
                    }
                    folds
                },
                attach_labels: p.attach_labels.clone(),
                attach_frames: c.count(t, "attach_frames", p.attach_frames, 0)?,
            }
        }
        _ => {
            return Err(c.err(
                "cloth",
                "",
                "needs exactly one of [cloth.grid], [cloth.mesh] or [cloth.pattern]",
                "keep one of the two sections",
            ))
        }
    })
}
