//! Seam lines: each seam segment as a thin dark ribbon facing the camera, lifted a little
//! towards it so that it wins the depth test against the cloth it lies on while the body and
//! the cloth in front still hide it.

use super::camera::Camera;
use super::colors::SEAM;
use super::render::DrawMesh;
use glam::Vec3;

/// The seam segments of a sewn pattern: consecutive particles along the first edge of each
/// stitch (once sewn, the second edge lies on it), as particle index pairs.
pub fn seam_segments(garment: &crate::pattern::garment::Garment) -> Vec<[u32; 2]> {
    (garment.seam_hinges.iter())
        .map(|h| [h.v[0], h.v[1]])
        .collect()
}

/// Ribbons along `segments` of the cloth at `positions`, about `width_px` pixels wide in an
/// image `height` px tall seen by `camera`.
pub fn seam_ribbons(
    positions: &[Vec3],
    segments: &[[u32; 2]],
    camera: &Camera,
    height: u32,
    width_px: f32,
) -> DrawMesh {
    let mut m = DrawMesh::default();
    // The size of one pixel at unit distance.
    let pixel = 2.0 * (0.5 * camera.fov_deg.to_radians()).tan() / height as f32;
    for &[a, b] in segments {
        let (Some(&p), Some(&q)) = (positions.get(a as usize), positions.get(b as usize)) else {
            continue;
        };
        let to_eye = camera.eye - 0.5 * (p + q);
        let distance = to_eye.length();
        if distance < 1e-6 {
            continue;
        }
        let half = 0.5 * width_px * pixel * distance;
        let along = (q - p).normalize_or_zero();
        let side = along.cross(to_eye).normalize_or_zero() * half;
        // 0.2% of the distance (6 mm at 3 m) clears the cloth's own triangles, which are flat
        // within a fraction of a millimetre between particles.
        let lift = to_eye / distance * (0.002 * distance);
        // Overlap neighbours by half the width so that joints have no gaps.
        let (p, q) = (p - along * half + lift, q + along * half + lift);
        let base = m.positions.len() as u32;
        m.positions.extend([p - side, p + side, q + side, q - side]);
        m.colors.extend([SEAM; 4]);
        m.triangles
            .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
    }
    m
}
