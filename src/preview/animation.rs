//! Animated GIFs: a run's written frames, played in real time and looping, with one fixed
//! camera (framing every frame's cloth) so that the picture does not jump between frames; and a
//! turntable, one frame seen from all around.

use super::camera::{Camera, CameraChoice};
use super::previewer::{Look, Previewer};
use crate::atomic_file::write_atomic;
use crate::error::Error;
use glam::{Quat, Vec3};
use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, RgbaImage};
use std::path::Path;

/// The most frames one animation holds; longer runs are thinned evenly, so that a GIF stays a
/// few MB and renders in seconds.
pub const MAX_ANIMATION_FRAMES: usize = 120;

/// Which of `frames` an animation shows: all of them, or every k-th (the last always).
pub fn pick_frames(frames: &[u32], max: usize) -> Vec<u32> {
    if frames.len() <= max {
        return frames.to_vec();
    }
    let stride = frames.len().div_ceil(max);
    let mut out: Vec<u32> = frames.iter().step_by(stride).copied().collect();
    if out.last() != frames.last() {
        out.push(*frames.last().expect("not empty"));
    }
    out
}

/// Renders the written `frames` (in order) with `look` and writes them to `out` as a looping
/// GIF whose frame delays follow the frames' simulated times at `fps`. Returns the frames shown.
pub fn write_gif(
    previewer: &mut Previewer,
    frames: &[u32],
    look: &Look,
    fps: f32,
    out: &Path,
) -> Result<usize, Error> {
    if frames.is_empty() {
        // A GIF of no frames is no animation: the previewer's error says why there are none.
        previewer.load(None)?;
    }
    let shown = pick_frames(frames, MAX_ANIMATION_FRAMES);
    // One box around the cloth of every shown frame.
    let mut framing: Option<(glam::Vec3, glam::Vec3)> = None;
    for &n in &shown {
        let f = previewer.load(Some(n))?;
        let (lo, hi) = previewer.framing_box(f.number, &f.positions);
        framing = Some(match framing {
            Some((a, b)) => (a.min(lo), b.max(hi)),
            None => (lo, hi),
        });
    }
    let (w, h) = look.size;
    let fail = |e: image::ImageError| Error::io(out, std::io::Error::other(e.to_string()));
    let mut gif = Vec::new();
    {
        // Speed 10 of 1..30: NeuQuant's usual trade of palette quality against time.
        let mut encoder = GifEncoder::new_with_speed(&mut gif, 10);
        encoder.set_repeat(Repeat::Infinite).map_err(fail)?;
        for (k, &n) in shown.iter().enumerate() {
            let pixels = previewer.image(Some(n), look, framing)?;
            // Shown until the next frame's time; the last one holds for a second.
            let ms = match shown.get(k + 1) {
                Some(&next) => (1000.0 * (next - n) as f32 / fps).round() as u32,
                None => 1000,
            };
            let image = RgbaImage::from_raw(w, h, pixels).expect("render returns w × h × 4 bytes");
            let frame = Frame::from_parts(image, 0, 0, Delay::from_numer_denom_ms(ms.max(20), 1));
            encoder.encode_frame(frame).map_err(fail)?;
        }
    }
    write_atomic(out, &gif)?;
    Ok(shown.len())
}

/// A turntable's steps: one turn in 10° steps.
pub const TURNTABLE_STEPS: u32 = 36;
/// Its steps per second: a turn in 3.6 s, slow enough to follow a fold around (GIF delays are
/// whole hundredths of a second, so 10 a second is exact).
const TURNTABLE_RATE: u32 = 10;

/// Renders frame `n` (`None`: the last) from `TURNTABLE_STEPS` cameras turned around the
/// vertical axis through what `look.camera` looks at, and writes them to `out` as a looping
/// GIF. A preset camera frames everything it will see on the way round, so that the garment
/// stays the same size as it turns. Returns the steps written.
pub fn write_turntable(
    previewer: &mut Previewer,
    n: Option<u32>,
    look: &Look,
    out: &Path,
) -> Result<usize, Error> {
    let f = previewer.load(n)?;
    let (w, h) = look.size;
    let start = match look.camera {
        CameraChoice::Custom(c) => c,
        CameraChoice::Preset(p) => {
            let (lo, hi) = previewer.framing_box(f.number, &f.positions);
            let (lo, hi) = turn_box(lo, hi);
            p.framing(lo, hi, w as f32 / h as f32)
        }
    };
    let fail = |e: image::ImageError| Error::io(out, std::io::Error::other(e.to_string()));
    let mut gif = Vec::new();
    {
        let mut encoder = GifEncoder::new_with_speed(&mut gif, 10);
        encoder.set_repeat(Repeat::Infinite).map_err(fail)?;
        for k in 0..TURNTABLE_STEPS {
            let mut step = look.clone();
            step.camera = CameraChoice::Custom(turned(start, k as f32 / TURNTABLE_STEPS as f32));
            let pixels = previewer.image(Some(f.number), &step, None)?;
            let image = RgbaImage::from_raw(w, h, pixels).expect("render returns w × h × 4 bytes");
            let delay = Delay::from_numer_denom_ms(1000, TURNTABLE_RATE);
            encoder
                .encode_frame(Frame::from_parts(image, 0, 0, delay))
                .map_err(fail)?;
        }
    }
    write_atomic(out, &gif)?;
    Ok(TURNTABLE_STEPS as usize)
}

/// The box that holds `lo..hi` turned by any angle about the vertical axis through its centre.
fn turn_box(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let c = 0.5 * (lo + hi);
    let r = 0.5 * Vec3::new(hi.x - lo.x, 0.0, hi.z - lo.z).length();
    (
        Vec3::new(c.x - r, lo.y, c.z - r),
        Vec3::new(c.x + r, hi.y, c.z + r),
    )
}

/// `camera` carried `turn` of a full turn around the vertical axis through its target.
fn turned(camera: Camera, turn: f32) -> Camera {
    let q = Quat::from_rotation_y(std::f32::consts::TAU * turn);
    Camera {
        eye: camera.target + q * (camera.eye - camera.target),
        ..camera
    }
}

#[cfg(test)]
mod tests {
    use super::pick_frames;

    #[test]
    fn thinning_keeps_the_last_frame() {
        let all: Vec<u32> = (0..10).map(|k| 6 * k).collect();
        assert_eq!(pick_frames(&all, 20), all);
        let few = pick_frames(&all, 4);
        assert_eq!(few, vec![0, 18, 36, 54]);
        let odd: Vec<u32> = (0..11).collect();
        assert_eq!(pick_frames(&odd, 5), vec![0, 3, 6, 9, 10]);
    }

    #[test]
    fn a_turn_keeps_the_distance_and_height_and_comes_round() {
        use super::{turn_box, turned, Camera, Vec3};
        let c = Camera {
            eye: Vec3::new(0.0, 1.5, 3.0),
            target: Vec3::new(0.0, 1.0, 0.0),
            fov_deg: 30.0,
        };
        let quarter = turned(c, 0.25);
        assert!(
            (quarter.eye - Vec3::new(3.0, 1.5, 0.0)).length() < 1e-5,
            "{}",
            quarter.eye
        );
        assert!((turned(c, 1.0).eye - c.eye).length() < 1e-5);
        // A 2 × 1 footprint turns inside a square of side √5.
        let (lo, hi) = turn_box(Vec3::new(-1.0, 0.0, -0.5), Vec3::new(1.0, 2.0, 0.5));
        assert!((hi.x - lo.x - 5f32.sqrt()).abs() < 1e-6 && hi.y == 2.0 && lo.y == 0.0);
    }
}
