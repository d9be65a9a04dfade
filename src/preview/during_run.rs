//! The previews `drapekit run` writes: every n-th frame as it is written
//! (`preview_<mode>_NNNN.png`), the last frame (`preview_<mode>.png`) and the animation
//! (`preview.gif`). A preview that cannot be rendered (no adapter at all) is a warning, not a
//! failed run: the frames and the summary are the results.

use super::animation::write_gif;
use super::previewer::Previewer;
use super::{scene_look, write_png, ColorMode};
use crate::error::Error;
use crate::gpu::AdapterChoice;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The animation's file name.
pub const GIF_FILE: &str = "preview.gif";

/// Renders a run's previews into its output folder as the scene asks.
pub struct RunPreviews<'a> {
    scene: &'a Scene,
    adapter: AdapterChoice,
    dir: PathBuf,
    previewer: Option<Previewer<'a>>,
    /// Set after the first failure, so that one missing adapter gives one warning.
    failed: bool,
    /// The frames this run wrote, in order (the folder may hold older ones from another run).
    written: Vec<u32>,
    /// The files written.
    pub names: Vec<String>,
    /// Why previews are missing.
    pub warnings: Vec<String>,
}

impl<'a> RunPreviews<'a> {
    /// Previews of `scene`'s run in `dir`, rendered on `adapter`.
    pub fn new(scene: &'a Scene, adapter: &AdapterChoice, dir: &Path) -> Self {
        RunPreviews {
            scene,
            adapter: adapter.clone(),
            dir: dir.to_path_buf(),
            previewer: None,
            failed: false,
            written: Vec::new(),
            names: Vec::new(),
            warnings: Vec::new(),
        }
    }

    /// Whether the scene asks for any preview.
    pub fn wanted(&self) -> bool {
        let p = &self.scene.preview;
        !p.last.is_empty() || p.every.is_some() || p.animation.is_some()
    }

    /// Runs `f` with the previewer (made on first use); a failure becomes a warning.
    fn with(&mut self, what: &str, f: impl FnOnce(&mut Previewer<'a>) -> Result<String, Error>) {
        if self.failed {
            return;
        }
        if self.previewer.is_none() {
            let fps = self.scene.solver.fps;
            match Previewer::new(&self.dir, Some(self.scene), fps, &self.adapter) {
                Ok(p) => self.previewer = Some(p),
                Err(e) => return self.warn(what, e),
            }
        }
        match f(self.previewer.as_mut().expect("made above")) {
            Ok(name) => self.names.push(name),
            Err(e) => self.warn(what, e),
        }
    }

    fn warn(&mut self, what: &str, e: Error) {
        let w = format!("{what} not rendered: {e}");
        crate::notice::warn(&w);
        self.warnings.push(w);
        self.failed = true;
    }

    /// After frame `frame`'s OBJ was written: the `[output] preview_every` previews.
    pub fn frame_written(&mut self, frame: u32) {
        self.written.push(frame);
        let Some(every) = self.scene.preview.every else {
            return;
        };
        if !frame.is_multiple_of(every) {
            return;
        }
        for mode in self.scene.preview.every_modes.clone() {
            let name = format!("preview_{mode}_{frame:04}.png");
            let path = self.dir.join(&name);
            let look = scene_look(Some(self.scene), mode.parse().expect("validated at load"));
            self.with(&format!("preview {name}"), |p| {
                let pixels = p.image(Some(frame), &look, None)?;
                write_png(&path, &pixels, look.size.0, look.size.1).map(|_| name)
            });
        }
    }

    /// After the run: the last frame's previews and the animation. Returns the names of every
    /// preview written and the warnings.
    pub fn finish(mut self) -> (Vec<String>, Vec<String>) {
        let Some(&last) = self.written.last() else {
            return (self.names, self.warnings);
        };
        for mode in self.scene.preview.last.clone() {
            let name = format!("preview_{mode}.png");
            let path = self.dir.join(&name);
            let look = scene_look(Some(self.scene), mode.parse().expect("validated at load"));
            self.with(&format!("preview {mode:?}"), |p| {
                let pixels = p.image(Some(last), &look, None)?;
                write_png(&path, &pixels, look.size.0, look.size.1).map(|_| name)
            });
        }
        if self.scene.preview.animation.is_some() {
            // The animation shows the first of the periodic modes (fabric by default).
            let mode: ColorMode = (self.scene.preview.every_modes.first())
                .map_or(ColorMode::Fabric, |m| m.parse().expect("validated at load"));
            let mut look = scene_look(Some(self.scene), mode);
            look.size = self.scene.preview.animation_size;
            let path = self.dir.join(GIF_FILE);
            let fps = self.scene.solver.fps;
            let frames = self.written.clone();
            self.with("animation", |p| {
                write_gif(p, &frames, &look, fps, &path).map(|_| GIF_FILE.to_string())
            });
        }
        (self.names, self.warnings)
    }
}
