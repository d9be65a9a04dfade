//! The coarse meshings of a scene's cloth for implicit Euler's multigrid solve: the grid with
//! half the columns and rows, or the sewing pattern meshed at twice the particle spacing,
//! level after level.

use super::multigrid::Multigrid;
use super::ClothModel;
use crate::mesh::Charted;
use crate::pattern::garment::{Garment, GarmentOptions};
use crate::pattern::Pattern;
use crate::scene::{ClothSource, Scene, INTEGRATOR_IMPLICIT};

/// Coarsening stops once a level has at most this many particles: the V-cycle's coarsest
/// level is solved by `plan::COARSEST_SWEEPS` symmetric Gauss–Seidel sweeps, which relax a
/// level this small (about 15 particles across).
pub const COARSEST_PARTICLES: usize = 40;

/// A coarser level must have at most this fraction of the particles of the level below it,
/// or coarsening stops (small panels stop shrinking once their outline sets their particles).
pub const MIN_REDUCTION: f64 = 0.6;

impl Scene {
    /// The multigrid hierarchy of the scene's cloth (`model`, with `garment` for patterns):
    /// `None` unless the scene steps by implicit Euler with multigrid on and its cloth is a
    /// grid or a pattern large enough to coarsen.
    pub fn build_multigrid(
        &self,
        model: &ClothModel,
        garment: Option<&Garment>,
    ) -> Option<Multigrid> {
        if self.solver.integrator != INTEGRATOR_IMPLICIT || !self.solver.multigrid {
            return None;
        }
        let (fine, coarser) = match (&self.cloth, garment) {
            (
                ClothSource::Grid {
                    width,
                    height,
                    columns,
                    rows,
                    ..
                },
                _,
            ) => grid_levels(*width, *height, *columns, *rows),
            (ClothSource::Pattern { path, options, .. }, Some(g)) => {
                let pattern = Pattern::load(path).ok()?;
                (g.charted(), pattern_levels(&pattern, options, g.uv.len()))
            }
            _ => return None,
        };
        if coarser.is_empty() || fine.len() != model.len() {
            return None;
        }
        Some(Multigrid::build(model, &fine, &coarser))
    }
}

/// The grid and its coarser grids, each with about half the columns and rows.
fn grid_levels(width: f32, height: f32, columns: u32, rows: u32) -> (Charted, Vec<Charted>) {
    let fine = Charted::grid(width, height, columns, rows);
    let mut levels = Vec::new();
    let (mut c, mut r) = (columns, rows);
    while (c * r) as usize > COARSEST_PARTICLES && c.min(r) > 3 {
        (c, r) = (c.div_ceil(2), r.div_ceil(2));
        levels.push(Charted::grid(width, height, c.max(2), r.max(2)));
    }
    (fine, levels)
}

/// The pattern meshed at twice, four times, … the particle spacing, while each level keeps
/// every panel and shrinks by `MIN_REDUCTION` at least.
fn pattern_levels(pattern: &Pattern, options: &GarmentOptions, fine_len: usize) -> Vec<Charted> {
    let mut levels = Vec::new();
    let mut len = fine_len;
    let mut spacing = options.particle_distance;
    while len > COARSEST_PARTICLES {
        spacing *= 2.0;
        let coarse = GarmentOptions {
            particle_distance: spacing,
            ..options.clone()
        };
        let Ok(g) = Garment::build(pattern, &coarse) else {
            break;
        };
        let chart = g.charted();
        let every_panel = (0..chart.charts as u32).all(|p| chart.triangle_chart.contains(&p));
        if !every_panel || chart.len() as f64 > MIN_REDUCTION * len as f64 {
            break;
        }
        len = chart.len();
        levels.push(chart);
    }
    levels
}
