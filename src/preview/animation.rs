//! An animated GIF of a run's written frames, played in real time and looping, with one fixed
//! camera (framing every frame's cloth) so that the picture does not jump between frames.

use super::previewer::{Look, Previewer};
use crate::atomic_file::write_atomic;
use crate::error::Error;
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
}
