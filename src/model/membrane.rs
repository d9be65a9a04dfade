//! The membrane triangles of a cloth whose fabric is orthotropic: each triangle's warp/weft
//! frame (the grain direction laid into the triangle's rest plane), the coefficients that give
//! the warp and weft directions' images from its vertices, and its stiffness and damping.

use super::layout::Membrane;
use crate::scene::Orthotropic;
use glam::{Mat2, Vec2, Vec3};

/// The membrane of `triangles` at rest `positions`, each triangle's warp along `grain[t]`
/// (any vector: its component in the triangle's plane is taken; a grain normal to the triangle
/// falls back to the triangle's first edge). Degenerate triangles get no membrane.
///
/// Damping is stiffness-proportional with the time constant τ = 2ζ·√(m/k) of the edge springs
/// the membrane replaces: k = k_max·2A/L̄² (an interior edge's spring, `ClothModel::from_mesh`),
/// m half a vertex's mass.
pub fn build_membranes(
    positions: &[Vec3],
    masses: &[f32],
    triangles: &[[u32; 3]],
    grain: &[Vec3],
    fabric: &Orthotropic,
    damping_ratio: f32,
) -> Vec<Membrane> {
    let mut out = Vec::with_capacity(triangles.len());
    for (t, &tri) in triangles.iter().enumerate() {
        let [x0, x1, x2] = tri.map(|v| positions[v as usize]);
        let Some(shape) = warp_weft_shape(x0, x1, x2, grain[t]) else {
            continue;
        };
        let area = 0.5 * (x1 - x0).cross(x2 - x0).length();
        let mean_sq_edge =
            ((x1 - x0).length_squared() + (x2 - x1).length_squared() + (x0 - x2).length_squared())
                / 3.0;
        let k_edge = fabric.warp.max(fabric.weft) * 2.0 * area / mean_sq_edge;
        let vertex_mass = tri.iter().map(|&v| masses[v as usize]).sum::<f32>() / 3.0;
        let tau = 2.0 * damping_ratio * (0.5 * vertex_mass / k_edge).sqrt();
        out.push(Membrane {
            v: [tri[0], tri[1], tri[2], 0],
            shape,
            stiffness: [
                fabric.warp * area,
                fabric.weft * area,
                fabric.shear * area,
                tau,
            ],
        });
    }
    out
}

/// A triangle's unit normal and its warp: `grain` laid into the triangle's plane, or its first
/// edge where the grain is normal to it. `None` for a degenerate triangle.
pub fn warp_in_plane(x0: Vec3, x1: Vec3, x2: Vec3, grain: Vec3) -> Option<(Vec3, Vec3)> {
    let e1 = x1 - x0;
    let n = e1.cross(x2 - x0).try_normalize()?;
    let warp = (grain - grain.dot(n) * n)
        .try_normalize()
        .or_else(|| e1.try_normalize())?;
    Some((n, warp))
}

/// (α₁, α₂, β₁, β₂) of a triangle: its warp and weft images are w_u = α₁(x₁ − x₀) + α₂(x₂ − x₀)
/// and w_v = β₁(x₁ − x₀) + β₂(x₂ − x₀), the columns of the deformation gradient F = D_s·D_m⁻¹
/// with D_m the rest edges in the warp/weft frame. `None` for a degenerate triangle.
pub fn warp_weft_shape(x0: Vec3, x1: Vec3, x2: Vec3, grain: Vec3) -> Option<[f32; 4]> {
    let (e1, e2) = (x1 - x0, x2 - x0);
    let (n, warp) = warp_in_plane(x0, x1, x2, grain)?;
    let weft = n.cross(warp);
    let rest = Mat2::from_cols(
        Vec2::new(e1.dot(warp), e1.dot(weft)),
        Vec2::new(e2.dot(warp), e2.dot(weft)),
    );
    if rest.determinant().abs() <= f32::EPSILON * e1.length_squared().max(e2.length_squared()) {
        return None;
    }
    let inv = rest.inverse();
    // F = D_s·inv: w_u = D_s·inv.col(0), w_v = D_s·inv.col(1).
    Some([inv.x_axis.x, inv.x_axis.y, inv.y_axis.x, inv.y_axis.y])
}

/// The warp direction of every triangle of a charted mesh whose 2D chart coordinates `uv`
/// the rest `positions` lay out without stretch (a sewing pattern's panels): the image of the
/// chart's x axis turned by `angle(triangle)` radians within the chart.
pub fn chart_grain(
    positions: &[Vec3],
    uv: &[Vec2],
    triangles: &[[u32; 3]],
    angle: impl Fn(usize) -> f32,
) -> Vec<Vec3> {
    triangles
        .iter()
        .enumerate()
        .map(|(t, tri)| {
            let [x0, x1, x2] = tri.map(|v| positions[v as usize]);
            let [u0, u1, u2] = tri.map(|v| uv[v as usize]);
            let chart = Mat2::from_cols(u1 - u0, u2 - u0);
            if chart.determinant() == 0.0 {
                return Vec3::X;
            }
            let (s, c) = angle(t).sin_cos();
            // The 2D direction in chart coordinates, then its image under the affine map
            // chart → world: [x₁ − x₀, x₂ − x₀]·chart⁻¹.
            let k = chart.inverse() * Vec2::new(c, s);
            k.x * (x1 - x0) + k.y * (x2 - x0)
        })
        .collect()
}

/// A grain at `angle` radians from world x, turned about world z (grids lie in the xy or xz
/// plane with their width along x; the triangle keeps the grain's in-plane part).
pub fn world_grain(triangles: usize, angle: f32, normal: Vec3) -> Vec<Vec3> {
    let rotation = glam::Quat::from_axis_angle(normal, angle);
    vec![rotation * Vec3::X; triangles]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_gives_unit_orthogonal_images_at_rest() {
        let (x0, x1, x2) = (
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(0.13, 0.21, 0.3),
            Vec3::new(0.11, 0.24, 0.31),
        );
        for grain in [Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Z] {
            let [a1, a2, b1, b2] = warp_weft_shape(x0, x1, x2, grain).unwrap();
            let wu = a1 * (x1 - x0) + a2 * (x2 - x0);
            let wv = b1 * (x1 - x0) + b2 * (x2 - x0);
            // f32 rounding of 3 cm edges and a 2×2 inverse: a few ulps of 1.
            assert!((wu.length() - 1.0).abs() < 1e-5, "{wu}");
            assert!((wv.length() - 1.0).abs() < 1e-5, "{wv}");
            assert!(wu.dot(wv).abs() < 1e-5);
            // The warp follows the grain's in-plane part.
            let n = (x1 - x0).cross(x2 - x0).normalize();
            let g = (grain - grain.dot(n) * n).normalize();
            assert!(wu.dot(g) > 1.0 - 1e-5, "{grain}: {wu}");
        }
        assert_eq!(warp_weft_shape(x0, x1, x0 + 2.0 * (x1 - x0), Vec3::X), None);
    }

    #[test]
    fn chart_grain_maps_the_chart_axis() {
        // A chart laid into the world turned 90° about z: chart x is world y.
        let uv = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
        let pos = [Vec3::ZERO, Vec3::Y, -Vec3::X];
        let g = chart_grain(&pos, &uv, &[[0, 1, 2]], |_| 0.0);
        assert!(g[0].distance(Vec3::Y) < 1e-6);
        let g = chart_grain(&pos, &uv, &[[0, 1, 2]], |_| std::f32::consts::FRAC_PI_2);
        assert!(g[0].distance(-Vec3::X) < 1e-6);
    }
}
