//! Progress bars on stderr for the long steps of a run (the body's distance-field bake, the
//! frames). The bake's bar is off unless the command line turns it on, so that a library
//! caller or a batch worker draws nothing; indicatif also draws nothing when stderr is not a
//! terminal.

use std::sync::atomic::{AtomicBool, Ordering};

static ENABLED: AtomicBool = AtomicBool::new(false);

/// Turns the bars on or off for this process (`drapekit run` turns them on unless `--quiet`).
pub fn enable(on: bool) {
    ENABLED.store(on, Ordering::Relaxed);
}

/// A bar of `len` steps with `message` before it, or a hidden one when bars are off.
pub fn bar(len: u64, message: String) -> indicatif::ProgressBar {
    if !ENABLED.load(Ordering::Relaxed) {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} {bar:30} {percent}%  {eta} left")
            .expect("a valid template"),
    );
    bar.set_message(message);
    bar
}

/// A frame counter with simulated time, throughput and the time left, on stderr; hidden when
/// `show` is off or stderr is not a terminal (indicatif draws nothing then).
pub fn frames(show: bool, frames: u32) -> indicatif::ProgressBar {
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(frames as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} frame {pos}/{len}  {msg}  {eta} left")
            .expect("a valid template"),
    );
    bar
}
