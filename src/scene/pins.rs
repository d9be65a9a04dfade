//! The `[[pins]]` tables: which particles are held fixed.

use super::cloth::ClothSource;
use super::raw::RawPin;
use crate::check::Checker;
use crate::error::InputError;
use glam::Vec3;

/// A grid corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corner {
    /// Highest row, first column.
    TopLeft,
    /// Highest row, last column.
    TopRight,
    /// Row 0, first column.
    BottomLeft,
    /// Row 0, last column.
    BottomRight,
}

/// A grid edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridEdge {
    /// The highest row.
    Top,
    /// Row 0.
    Bottom,
    /// The first column.
    Left,
    /// The last column.
    Right,
}

/// Which particles one `[[pins]]` entry holds fixed.
#[derive(Clone, Debug, PartialEq)]
pub enum PinSelection {
    /// Named grid corners.
    Corners(Vec<Corner>),
    /// A whole grid edge.
    Edge(GridEdge),
    /// Particle indices.
    Indices(Vec<u32>),
    /// Every particle whose initial position lies in the box (m).
    Box {
        /// Minimum corner.
        min: Vec3,
        /// Maximum corner.
        max: Vec3,
    },
}

/// Validates `[[pins]]`; named corners and edges need a grid.
pub(super) fn parse(
    c: &Checker,
    raw: &[RawPin],
    cloth: &ClothSource,
) -> Result<Vec<PinSelection>, InputError> {
    let mut pins = Vec::new();
    for (k, p) in raw.iter().enumerate() {
        let table = format!("pins[{k}]");
        let given = [
            p.corners.is_some(),
            p.edge.is_some(),
            p.indices.is_some(),
            p.box_min_m.is_some() || p.box_max_m.is_some(),
        ];
        if given.iter().filter(|&&g| g).count() != 1 {
            return Err(c.err(
                &table,
                "",
                "needs exactly one selector",
                "give one of corners, edge, indices, or box_min_m with box_max_m",
            ));
        }
        let is_grid = matches!(cloth, ClothSource::Grid { .. });
        let selection = if let Some(names) = &p.corners {
            if !is_grid {
                return Err(c.err(
                    &table,
                    "corners",
                    "named corners exist only for [cloth.grid]",
                    "select mesh particles with indices or box_min_m/box_max_m",
                ));
            }
            let mut corners = Vec::new();
            for name in names {
                corners.push(match name.as_str() {
                    "top-left" => Corner::TopLeft,
                    "top-right" => Corner::TopRight,
                    "bottom-left" => Corner::BottomLeft,
                    "bottom-right" => Corner::BottomRight,
                    other => {
                        return Err(c.err(
                            &table,
                            "corners",
                            format!("unknown corner {other:?}"),
                            "use top-left, top-right, bottom-left or bottom-right",
                        ))
                    }
                });
            }
            PinSelection::Corners(corners)
        } else if let Some(name) = &p.edge {
            if !is_grid {
                return Err(c.err(
                    &table,
                    "edge",
                    "named edges exist only for [cloth.grid]",
                    "select mesh particles with indices or box_min_m/box_max_m",
                ));
            }
            PinSelection::Edge(match name.as_str() {
                "top" => GridEdge::Top,
                "bottom" => GridEdge::Bottom,
                "left" => GridEdge::Left,
                "right" => GridEdge::Right,
                other => {
                    return Err(c.err(
                        &table,
                        "edge",
                        format!("unknown edge {other:?}"),
                        "use top, bottom, left or right",
                    ))
                }
            })
        } else if let Some(ids) = &p.indices {
            let mut out = Vec::new();
            for &i in ids {
                if i < 0 || i > u32::MAX as i64 {
                    return Err(c.err(
                        &table,
                        "indices",
                        format!("{i} is not a particle index"),
                        "use 0-based particle indices",
                    ));
                }
                out.push(i as u32);
            }
            PinSelection::Indices(out)
        } else {
            let (Some(min), Some(max)) = (p.box_min_m, p.box_max_m) else {
                return Err(c.err(
                    &table,
                    "",
                    "a box needs both box_min_m and box_max_m",
                    "add the missing corner",
                ));
            };
            PinSelection::Box {
                min: c.vec3(&table, "box_min_m", min)?,
                max: c.vec3(&table, "box_max_m", max)?,
            }
        };
        pins.push(selection);
    }
    Ok(pins)
}
