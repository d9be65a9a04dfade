//! Position error against the reference at the same simulated time. At the same resolution
//! particles correspond one to one; across resolutions each particle is matched, through its 2D
//! material coordinate (pattern UV, or its place in the flat grid), with the point of the
//! reference cloth at the same coordinate (barycentric on the reference's triangle there).

use crate::mesh::GridPlane;
use crate::scene::{ClothSource, Scene};
use crate::sim::Prepared;
use glam::{Vec2, Vec3};

/// Where each particle sits in the flat cloth, and the flat triangles.
#[derive(Clone, Debug)]
pub struct Material {
    /// 2D coordinate per particle, in m.
    pub uv: Vec<Vec2>,
    /// Panel per particle (0 for a grid).
    pub panel: Vec<u32>,
    /// The cloth's triangles.
    pub triangles: Vec<[u32; 3]>,
}

impl Material {
    /// The material coordinates of a prepared pattern or grid cloth (`None` for an OBJ cloth).
    pub fn of(scene: &Scene, prep: &Prepared) -> Option<Material> {
        if let Some(g) = &prep.garment {
            let mut panel = vec![0u32; g.uv.len()];
            for (t, &p) in g.mesh.triangles.iter().zip(&g.triangle_panel) {
                for &i in t {
                    panel[i as usize] = p;
                }
            }
            return Some(Material {
                uv: g.uv.clone(),
                panel,
                triangles: g.mesh.triangles.clone(),
            });
        }
        let ClothSource::Grid { plane, .. } = &scene.cloth else {
            return None;
        };
        // The grid starts flat: its initial positions are its material coordinates.
        let uv = (prep.model.positions.iter())
            .map(|p| match plane {
                GridPlane::Xy => Vec2::new(p.x, p.y),
                GridPlane::Xz => Vec2::new(p.x, p.z),
            })
            .collect::<Vec<_>>();
        Some(Material {
            panel: vec![0; uv.len()],
            uv,
            triangles: prep.model.triangles.clone(),
        })
    }
}

/// A cloth's state at the comparison time, with what maps it onto another resolution.
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// Positions in m.
    pub positions: Vec<Vec3>,
    /// The resolution it was built at (the particle distance multiple).
    pub spacing: f32,
    /// Its material coordinates, if it has any.
    pub material: Option<Material>,
}

/// How far a cloth lies from the reference, over matched particles, in m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionError {
    /// Root mean square distance.
    pub rms: f64,
    /// Largest distance.
    pub max: f64,
    /// Length of the mean displacement: how far the cloth as a whole sits from the reference
    /// (folds that form in other places largely average out of it).
    pub shift: f64,
}

impl PositionError {
    /// No figures.
    pub const NAN: PositionError = PositionError {
        rms: f64::NAN,
        max: f64::NAN,
        shift: f64::NAN,
    };
}

/// How far `point` lies from `reference`, or why they cannot be compared.
pub fn position_error(point: &Snapshot, reference: &Snapshot) -> Result<PositionError, String> {
    let same =
        point.spacing == reference.spacing && point.positions.len() == reference.positions.len();
    let offsets: Vec<glam::DVec3> = if same {
        (point.positions.iter().zip(&reference.positions))
            .map(|(a, b)| (*a - *b).as_dvec3())
            .collect()
    } else {
        let (Some(pm), Some(rm)) = (&point.material, &reference.material) else {
            return Err("different resolutions and no material coordinates to map them".into());
        };
        (point.positions.iter().enumerate())
            .map(|(i, x)| {
                let target = locate(rm, pm.panel[i], pm.uv[i]);
                let q = target.map_or(Vec3::NAN, |(t, w)| {
                    let [a, b, c] = rm.triangles[t].map(|v| reference.positions[v as usize]);
                    w.x * a + w.y * b + w.z * c
                });
                (*x - q).as_dvec3()
            })
            .collect()
    };
    if offsets.iter().any(|d| !d.is_finite()) {
        return Err("a particle has no counterpart on the reference cloth".into());
    }
    let n = offsets.len().max(1) as f64;
    Ok(PositionError {
        rms: (offsets.iter().map(|d| d.length_squared()).sum::<f64>() / n).sqrt(),
        max: offsets.iter().map(|d| d.length()).fold(0.0, f64::max),
        shift: (offsets.iter().sum::<glam::DVec3>() / n).length(),
    })
}

/// The reference triangle of `panel` that holds `uv` (or, outside every triangle, as where a
/// coarser outline cuts a curve differently, the nearest one) and the barycentric weights of
/// the nearest point on it.
fn locate(m: &Material, panel: u32, uv: Vec2) -> Option<(usize, Vec3)> {
    let mut best: Option<(f32, usize, Vec3)> = None;
    for (k, t) in m.triangles.iter().enumerate() {
        if m.panel[t[0] as usize] != panel {
            continue;
        }
        let [a, b, c] = t.map(|v| m.uv[v as usize]);
        let w = nearest_barycentric(uv, a, b, c);
        let q = w.x * a + w.y * b + w.z * c;
        let d = q.distance_squared(uv);
        if best.is_none_or(|(bd, _, _)| d < bd) {
            best = Some((d, k, w));
            if d == 0.0 {
                break;
            }
        }
    }
    best.map(|(_, k, w)| (k, w))
}

/// Barycentric weights of the point of triangle (a, b, c) nearest to p, in 2D.
fn nearest_barycentric(p: Vec2, a: Vec2, b: Vec2, c: Vec2) -> Vec3 {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let d00 = v0.dot(v0);
    let d01 = v0.dot(v1);
    let d11 = v1.dot(v1);
    let denom = d00 * d11 - d01 * d01;
    if denom > 0.0 {
        let (d20, d21) = (v2.dot(v0), v2.dot(v1));
        let v = (d11 * d20 - d01 * d21) / denom;
        let w = (d00 * d21 - d01 * d20) / denom;
        if v >= 0.0 && w >= 0.0 && v + w <= 1.0 {
            return Vec3::new(1.0 - v - w, v, w);
        }
    }
    // Outside (or degenerate): the nearest point lies on an edge.
    let on_edge = |p: Vec2, s: Vec2, e: Vec2| {
        let d = e - s;
        let len2 = d.length_squared();
        let t = if len2 > 0.0 {
            ((p - s).dot(d) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (t, (s + t * d).distance_squared(p))
    };
    let (tab, dab) = on_edge(p, a, b);
    let (tbc, dbc) = on_edge(p, b, c);
    let (tca, dca) = on_edge(p, c, a);
    if dab <= dbc && dab <= dca {
        Vec3::new(1.0 - tab, tab, 0.0)
    } else if dbc <= dca {
        Vec3::new(0.0, 1.0 - tbc, tbc)
    } else {
        Vec3::new(tca, 0.0, 1.0 - tca)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(n: u32, lift: impl Fn(Vec2) -> Vec3) -> Snapshot {
        let mesh = crate::mesh::TriMesh::grid(1.0, 1.0, n, n, Vec3::ZERO, GridPlane::Xy);
        let uv: Vec<Vec2> = mesh.positions.iter().map(|p| p.truncate()).collect();
        Snapshot {
            positions: uv.iter().map(|&p| lift(p)).collect(),
            spacing: 1.0 / (n - 1) as f32,
            material: Some(Material {
                panel: vec![0; uv.len()],
                uv,
                triangles: mesh.triangles,
            }),
        }
    }

    #[test]
    fn a_linear_deformation_maps_exactly_across_resolutions() {
        // Barycentric interpolation reproduces an affine map exactly (up to f32 rounding).
        let lift = |p: Vec2| Vec3::new(2.0 * p.x + 0.1, p.y - 0.3 * p.x, 0.5 * p.y);
        let e = position_error(&square(7, lift), &square(12, lift)).unwrap();
        assert!(e.max < 1e-6, "{e:?}");
    }

    #[test]
    fn a_uniform_shift_is_its_own_error() {
        let reference = square(9, |p| p.extend(0.0));
        let point = square(5, |p| p.extend(0.01));
        let e = position_error(&point, &reference).unwrap();
        // f32 positions of about 1 m hold 0.01 m to about 1e-7 m.
        for v in [e.rms, e.max, e.shift] {
            assert!((v - 0.01).abs() < 1e-6, "{e:?}");
        }
    }

    #[test]
    fn outside_points_take_the_nearest_edge() {
        let w = nearest_barycentric(Vec2::new(0.5, -1.0), Vec2::ZERO, Vec2::X, Vec2::Y);
        assert!((w - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6, "{w}");
    }
}
