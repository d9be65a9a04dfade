//! The PC2 point cache (Blender's Mesh Cache modifier, 3ds Max's Point Cache): a 32-byte
//! header, then every sample's points as little-endian f32 x, y, z.

use glam::Vec3;

/// The header's signature, NUL included.
pub const SIGNATURE: &[u8; 12] = b"POINTCACHE2\0";

/// The PC2 file of `samples` (each one position per point, all the same length). `start_frame`
/// is the first sample's frame and `sample_rate` the frames between samples. `None` when the
/// counts do not fit the header's 32-bit fields or the samples differ in length.
pub fn pc2_bytes(samples: &[Vec<Vec3>], start_frame: f32, sample_rate: f32) -> Option<Vec<u8>> {
    let points = samples.first().map_or(0, Vec::len);
    if samples.iter().any(|s| s.len() != points) {
        return None;
    }
    let mut b = Vec::with_capacity(32 + 12 * points * samples.len());
    b.extend_from_slice(SIGNATURE);
    b.extend_from_slice(&1i32.to_le_bytes());
    b.extend_from_slice(&i32::try_from(points).ok()?.to_le_bytes());
    b.extend_from_slice(&start_frame.to_le_bytes());
    b.extend_from_slice(&sample_rate.to_le_bytes());
    b.extend_from_slice(&i32::try_from(samples.len()).ok()?.to_le_bytes());
    for p in samples.iter().flatten() {
        for c in p.to_array() {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    Some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_layout() {
        let samples = vec![vec![Vec3::ZERO, Vec3::X], vec![Vec3::Y, Vec3::Z]];
        let b = pc2_bytes(&samples, 0.0, 6.0).unwrap();
        assert_eq!(b.len(), 32 + 2 * 2 * 12);
        assert_eq!(&b[..12], SIGNATURE);
        let word = |at: usize| <[u8; 4]>::try_from(&b[at..at + 4]).unwrap();
        assert_eq!(i32::from_le_bytes(word(12)), 1);
        assert_eq!(i32::from_le_bytes(word(16)), 2);
        assert_eq!(f32::from_le_bytes(word(24)), 6.0);
        assert_eq!(i32::from_le_bytes(word(28)), 2);
        // Sample 1, point 0 is +y.
        assert_eq!(f32::from_le_bytes(word(32 + 24 + 4)), 1.0);
        assert!(pc2_bytes(&[vec![Vec3::ZERO], vec![]], 0.0, 1.0).is_none());
    }
}
