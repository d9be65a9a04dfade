//! Previews: PNGs of the frames of a run, the garment and the body rendered with wgpu (any
//! adapter, the software one included), in fabric, strain or penetration colours with a
//! legend, optionally with the seams drawn; and an animated GIF of the run.

mod animation;
mod camera;
mod colors;
mod during_run;
mod fabric_look;
mod font;
mod legend;
mod obj_frame;
mod occlusion;
mod previewer;
mod render;
mod seams;

pub use animation::{
    pick_frames, write_gif, write_turntable, MAX_ANIMATION_FRAMES, TURNTABLE_STEPS,
};
pub use camera::{Camera, CameraChoice, CameraPreset, PRESET_FOV_DEG};
pub use colors::{
    panel_color, penetration_legend, strain_legend, strain_ramp, triangle_strain, ColorMode,
    Legend, PenetrationScale, BODY, FABRIC, PALETTE, SEAM,
};
pub use during_run::{RunPreviews, GIF_FILE};
pub use fabric_look::{fabric_color, fabric_strain_max, FabricLook, LOOKS};
pub use legend::{draw_legend, srgb_byte, text_scale, LegendBox};
pub use obj_frame::{frames, read_obj, FrameMesh};
pub use occlusion::{ambient_occlusion, REACH as OCCLUSION_REACH};
pub use previewer::{Look, Previewer};
pub use render::{render, render_textured, DrawMesh, FabricTexture, SHADER};
pub use seams::seam_ribbons;

use crate::atomic_file::write_atomic;
use crate::error::Error;
use crate::gpu::AdapterChoice;
use crate::scene::{CameraSetting, Scene, DEFAULT_STRAIN_MAX};
use previewer::bad;
use std::path::{Path, PathBuf};

/// The camera a scene's `[preview] camera` names.
pub fn scene_camera(setting: &CameraSetting) -> CameraChoice {
    match setting {
        CameraSetting::Preset(name) => {
            CameraChoice::Preset(name.parse().expect("validated at load"))
        }
        CameraSetting::Custom {
            eye,
            target,
            fov_deg,
        } => CameraChoice::Custom(Camera {
            eye: *eye,
            target: *target,
            fov_deg: *fov_deg,
        }),
    }
}

/// The look a scene asks for in `mode` (its camera, size, strain maximum and seams), or the
/// defaults without a scene.
pub fn scene_look(scene: Option<&Scene>, mode: ColorMode) -> Look {
    match scene {
        Some(s) => Look {
            camera: scene_camera(&s.preview.camera),
            mode,
            size: s.preview.size,
            strain_max: (s.preview.strain_max).unwrap_or_else(|| fabric_strain_max(&s.fabric)),
            seams: s.preview.seams,
            legend: true,
            // The scene's colours per panel (tinting the fabric image, if any), else the
            // fabric's one colour for every panel, or the image's own.
            colors: match (s.preview.colors.is_empty(), &s.preview.texture) {
                (false, _) => s.preview.colors.clone(),
                (true, Some(_)) => vec![glam::Vec3::ONE],
                (true, None) => vec![fabric_color(&s.fabric)],
            },
            checker: s.preview.checker.unwrap_or(0.0),
            occlusion: mode == ColorMode::Fabric,
            texture: s.preview.texture.clone(),
        },
        None => Look {
            camera: CameraChoice::Preset(CameraPreset::ThreeQuarter),
            mode,
            size: (1280, 960),
            strain_max: DEFAULT_STRAIN_MAX,
            seams: false,
            legend: true,
            colors: Vec::new(),
            checker: 0.0,
            occlusion: mode == ColorMode::Fabric,
            texture: None,
        },
    }
}

/// Reads a run's `summary.json` and loads the scene it ran (its copy in the folder, see
/// `run_folder::run_scene`) and its fps.
pub fn run_scene_of(run: &Path) -> Result<(Option<Scene>, f32), Error> {
    let (scene, fps, _) = run_summary(run)?;
    Ok((scene, fps))
}

/// A run folder's frames as its summary lists them: frame numbers and files.
type FrameList = Vec<(u32, PathBuf)>;

/// Whether `run` holds files a run writes before its summary (a run stopped before it
/// finished).
fn stopped_run(run: &Path) -> bool {
    [
        "frame_0000.obj",
        crate::run_folder::SCENE_COPY,
        "checkpoint.bin",
    ]
    .iter()
    .any(|f| run.join(f).is_file())
}

/// `run_scene_of`, and the frames the summary lists.
fn run_summary(run: &Path) -> Result<(Option<Scene>, f32, Option<FrameList>), Error> {
    let summary_path = run.join("summary.json");
    let summary: serde_json::Value = std::fs::read(&summary_path)
        .map_err(|e| match e.kind() {
            // A run's files but no summary: a run killed before it finished (the scene's
            // copy is written first; frames only with OBJ output).
            std::io::ErrorKind::NotFound if stopped_run(run) => bad(
                &summary_path,
                "the run in this folder has no summary: it was stopped before it finished"
                    .to_string(),
                "continue it with drapekit resume (if it wrote a checkpoint) or rerun it; its \
                 frames open in any OBJ viewer meanwhile",
            ),
            _ => Error::io(&summary_path, e),
        })
        .and_then(|b| {
            serde_json::from_slice(&b).map_err(|e| {
                bad(
                    &summary_path,
                    format!("not a drapekit summary: {e}"),
                    "rerun drapekit run",
                )
            })
        })?;
    let scene = crate::run_folder::run_scene(run, &summary)?;
    let fps = summary["fps"].as_f64().unwrap_or(24.0) as f32;
    if !(fps.is_finite() && fps > 0.0) {
        // Frame times (and a GIF's delays) are frame numbers over it.
        return Err(bad(
            &summary_path,
            format!("its fps, {fps}, is not a positive number of frames per second"),
            "rerun drapekit run (the summary is damaged)",
        ));
    }
    let frames = crate::run_folder::summary_frames(run, &summary);
    Ok((scene, fps, frames))
}

/// Renders frame `frame` (`None`: the last) of the run in `run` and writes it to `out` as a
/// PNG; or, when `out` ends in `.gif`, every frame of the run as an animation, or with
/// `turntable` that frame seen from all around (at the scene's `[preview] animation_size`
/// unless `adjust` sets a size). The look starts from the run's scene (`[preview]`) and
/// `adjust` changes it (the command line's options).
pub fn preview_run(
    run: &Path,
    frame: Option<u32>,
    mode: ColorMode,
    adapter: &AdapterChoice,
    adjust: impl FnOnce(&mut Look),
    turntable: bool,
    out: &Path,
) -> Result<(), Error> {
    let gif = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    if turntable && !gif {
        return Err(bad(
            out,
            "a turntable is an animation",
            "write it to a .gif (e.g. --out spin.gif)",
        ));
    }
    if gif && frame.is_some() && !turntable {
        return Err(bad(
            out,
            "a .gif shows every frame, and --frame picks one",
            "leave out --frame, or write a .png",
        ));
    }
    let (scene, fps, listed) = run_summary(run)?;
    let mut look = scene_look(scene.as_ref(), mode);
    if gif {
        look.size = scene
            .as_ref()
            .map_or((480, 360), |s| s.preview.animation_size);
    }
    adjust(&mut look);
    let mut previewer = Previewer::new(run, scene.as_ref(), fps, adapter)?;
    if let Some(listed) = listed {
        previewer.use_frames(listed);
    }
    if gif {
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        if turntable {
            return write_turntable(&mut previewer, frame, &look, out).map(|_| ());
        }
        let frames: Vec<u32> = previewer
            .frame_files()?
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        return write_gif(&mut previewer, &frames, &look, fps, out).map(|_| ());
    }
    let pixels = previewer.image(frame, &look, None)?;
    write_png(out, &pixels, look.size.0, look.size.1)
}

/// Encodes RGBA8 pixels as a PNG and writes it atomically.
pub fn write_png(out: &Path, pixels: &[u8], width: u32, height: u32) -> Result<(), Error> {
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        pixels,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )
    .map_err(|e| Error::io(out, std::io::Error::other(e.to_string())))?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    write_atomic(out, &png)
}
