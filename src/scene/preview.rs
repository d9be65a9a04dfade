//! What the previews of a run look like and when they are rendered: the `[preview]` table, plus
//! the preview keys of `[output]` (`previews`, `preview_every`, `preview_modes`, and the older
//! `preview_camera`, which `[preview] camera` replaces).

use super::raw::{RawCamera, RawOutput, RawPreview};
use crate::check::Checker;
use crate::error::InputError;
use glam::Vec3;

/// The colour modes a preview can use.
pub const PREVIEW_MODES: &[&str] = &["fabric", "strain", "penetration"];
/// The camera presets.
pub const CAMERA_PRESETS: &[&str] = &["front", "back", "side", "three-quarter"];
/// The strain shown in full red when neither `[preview] strain_max` nor the fabric gives one:
/// 20%.
pub const DEFAULT_STRAIN_MAX: f32 = 0.2;

/// The previews' camera, as the scene gives it.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraSetting {
    /// A preset name from `CAMERA_PRESETS`, framing the cloth.
    Preset(String),
    /// A fixed camera in m and degrees.
    Custom {
        /// Eye position.
        eye: Vec3,
        /// Point looked at.
        target: Vec3,
        /// Vertical field of view.
        fov_deg: f32,
    },
}

/// Preview settings.
#[derive(Clone, Debug, PartialEq)]
pub struct PreviewSettings {
    /// Modes rendered of the last frame as `preview_<mode>.png`.
    pub last: Vec<String>,
    /// Render every n-th frame as well (on the `[output] every` schedule), or never.
    pub every: Option<u32>,
    /// The modes of those, `preview_<mode>_NNNN.png`.
    pub every_modes: Vec<String>,
    /// The camera.
    pub camera: CameraSetting,
    /// The strain shown in full red, as a fraction (0.2 = 20%); `None`: the fabric's range.
    pub strain_max: Option<f32>,
    /// Draw the seams as dark lines.
    pub seams: bool,
    /// Image size in pixels.
    pub size: (u32, u32),
    /// `Some("gif")`: an animation of the written frames, `preview.gif`.
    pub animation: Option<String>,
    /// The animation's frame size in pixels.
    pub animation_size: (u32, u32),
    /// Fabric colours per panel, in pattern order and repeating, as linear RGB (empty: the
    /// built-in palette).
    pub colors: Vec<Vec3>,
    /// The checker's square size in pattern coordinates, in m (`None`: no checker).
    pub checker: Option<f32>,
    /// A fabric image laid over the pattern coordinates (`None`: plain colours).
    pub texture: Option<TextureSetting>,
}

/// `[preview] texture` and `texture_size_m`: an image of the fabric, tiled over each panel's
/// pattern coordinates with its vertical axis along the panel's y axis (the grain line of a
/// GarmentCode drawing).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSetting {
    /// The PNG file, resolved against the scene's folder.
    pub path: std::path::PathBuf,
    /// The physical width and height one copy of the image covers, in m.
    pub size_m: [f32; 2],
    /// The image's width and height in pixels.
    pub pixels: (u32, u32),
}

/// `"#rrggbb"` (sRGB) as linear RGB.
pub fn hex_color(s: &str) -> Option<Vec3> {
    let hex = s.strip_prefix('#').filter(|h| h.len() == 6)?;
    let byte = |k: usize| u8::from_str_radix(hex.get(k..k + 2)?, 16).ok();
    let linear = |b: u8| {
        let c = b as f32 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    Some(Vec3::new(
        linear(byte(0)?),
        linear(byte(2)?),
        linear(byte(4)?),
    ))
}

fn modes(c: &Checker, table: &str, key: &str, list: &[String]) -> Result<(), InputError> {
    for mode in list {
        if !PREVIEW_MODES.contains(&mode.as_str()) {
            return Err(c.err(
                table,
                key,
                format!("unknown preview mode {mode:?}"),
                "use \"fabric\", \"strain\" and/or \"penetration\"",
            ));
        }
    }
    Ok(())
}

/// A preview size: each side from 16 to 3840 px (4K UHD is 3840×2160), as `--size` allows.
fn size(c: &Checker, key: &str, v: [i64; 2]) -> Result<(u32, u32), InputError> {
    for n in v {
        if !(16..=3840).contains(&n) {
            return Err(c.err(
                "preview",
                key,
                format!("{n} px is outside 16 to 3840"),
                "give [width, height] in pixels, each from 16 to 3840, e.g. [1280, 960]",
            ));
        }
    }
    Ok((v[0] as u32, v[1] as u32))
}

/// Validates a camera: a preset name, or a finite eye and target apart, not looking straight
/// up or down (the view's up direction is +y), with a field of view in (1°, 170°).
pub(super) fn camera(
    c: &Checker,
    table: &str,
    raw: &RawCamera,
) -> Result<CameraSetting, InputError> {
    match raw {
        RawCamera::Preset(name) => {
            if CAMERA_PRESETS.contains(&name.as_str()) {
                Ok(CameraSetting::Preset(name.clone()))
            } else {
                Err(c.err(
                    table,
                    "camera",
                    format!(
                        "unknown camera {name:?}{}",
                        crate::suggest::did_you_mean(name, CAMERA_PRESETS.iter().copied())
                    ),
                    "use front, back, side, three-quarter, or { eye = [x, y, z], target = [x, y, z], fov_deg = 30 }",
                ))
            }
        }
        RawCamera::Custom {
            eye,
            target,
            fov_deg,
        } => {
            let eye = c.vec3(table, "camera", *eye)?;
            let target = c.vec3(table, "camera", *target)?;
            let fov = c.finite(table, "camera", *fov_deg)?;
            if !(*fov_deg > 1.0 && *fov_deg < 170.0) {
                return Err(c.err(
                    table,
                    "camera",
                    format!("fov_deg = {fov_deg} is outside (1, 170) degrees"),
                    "give a vertical field of view between 1 and 170 degrees, e.g. 30",
                ));
            }
            let d = target - eye;
            if d.length() < 1e-4 {
                return Err(c.err(
                    table,
                    "camera",
                    "eye and target are the same point",
                    "move the eye away from the target (both in m)",
                ));
            }
            if d.normalize().y.abs() > 0.9999 {
                return Err(c.err(
                    table,
                    "camera",
                    "the camera looks straight up or down, so +y cannot be its up direction",
                    "move the eye sideways a little (e.g. 1 cm in z)",
                ));
            }
            Ok(CameraSetting::Custom {
                eye,
                target,
                fov_deg: fov,
            })
        }
    }
}

/// Validates `[preview]` and the preview keys of `[output]`.
pub(super) fn parse(
    c: &Checker,
    out: &RawOutput,
    raw: Option<&RawPreview>,
    obj: bool,
) -> Result<PreviewSettings, InputError> {
    let default = RawPreview::default();
    let p = raw.unwrap_or(&default);
    modes(c, "output", "previews", &out.previews)?;
    modes(c, "output", "preview_modes", &out.preview_modes)?;
    let every = match out.preview_every {
        None => None,
        Some(n) => {
            let n = c.count("output", "preview_every", n, 1)?;
            // Previews are rendered from the OBJ frames, which are written every `every`.
            if out.every >= 1 && n as i64 % out.every != 0 {
                return Err(c.err(
                    "output",
                    "preview_every",
                    format!("{n} is not a multiple of every = {}", out.every),
                    format!(
                        "use a multiple of {} (previews are rendered from written frames)",
                        out.every
                    ),
                ));
            }
            Some(n)
        }
    };
    let camera = match (&out.preview_camera, &p.camera) {
        (Some(_), Some(_)) => {
            return Err(c.err(
                "output",
                "preview_camera",
                "the camera is given twice, here and as [preview] camera",
                "remove [output] preview_camera (the older spelling) and keep [preview] camera",
            ))
        }
        (Some(name), None) => {
            camera(c, "output", &RawCamera::Preset(name.clone())).map_err(|_| {
                c.err(
                    "output",
                    "preview_camera",
                    format!(
                        "unknown camera {name:?}{}",
                        crate::suggest::did_you_mean(name, CAMERA_PRESETS.iter().copied())
                    ),
                    "use front, back, side or three-quarter",
                )
            })?
        }
        (None, Some(cam)) => camera(c, "preview", cam)?,
        (None, None) => CameraSetting::Preset("three-quarter".into()),
    };
    let animation = match p.animation.as_deref() {
        None | Some("none") => None,
        Some("gif") => Some("gif".to_string()),
        Some(other) => {
            return Err(c.err(
                "preview",
                "animation",
                format!("unknown animation format {other:?}"),
                "use \"gif\" (or \"none\")",
            ))
        }
    };
    let wants = !out.previews.is_empty() || every.is_some() || animation.is_some();
    if wants && !obj {
        return Err(c.err(
            "output",
            "",
            "previews are rendered from the OBJ frames, and no OBJ frames are written",
            "write OBJ frames (obj = true, or \"obj\" in formats), or remove the previews",
        ));
    }
    Ok(PreviewSettings {
        last: out.previews.clone(),
        every,
        every_modes: if out.preview_modes.is_empty() {
            vec!["fabric".to_string()]
        } else {
            out.preview_modes.clone()
        },
        camera,
        strain_max: match p.strain_max {
            None => None,
            Some(v) => {
                let v = c.finite("preview", "strain_max", v)?;
                if !(0.001..=5.0).contains(&v) {
                    return Err(c.err(
                        "preview",
                        "strain_max",
                        format!("{v} is outside 0.001 to 5 (it is a fraction, not a percentage)"),
                        "write e.g. 0.2 for 20%",
                    ));
                }
                Some(v)
            }
        },
        seams: p.seams,
        size: size(c, "size", p.size)?,
        animation,
        animation_size: size(c, "animation_size", p.animation_size)?,
        colors: (p.colors.iter())
            .map(|h| {
                hex_color(h).ok_or_else(|| {
                    c.err(
                        "preview",
                        "colors",
                        format!("{h:?} is not a colour"),
                        "write sRGB colours as \"#rrggbb\", e.g. [\"#5991ce\", \"#d9a441\"]",
                    )
                })
            })
            .collect::<Result<_, _>>()?,
        checker: match p.checker_m {
            None => None,
            Some(v) => Some(c.within("preview", "checker_m", v, (1e-3, 10.0), "m")?),
        },
        texture: texture(c, p)?,
    })
}

/// Validates `texture` and `texture_size_m`: a PNG that exists and decodes its header, tiled
/// at a physical size from 1 mm to 10 m.
fn texture(c: &Checker, p: &RawPreview) -> Result<Option<TextureSetting>, InputError> {
    let Some(name) = &p.texture else {
        if p.texture_size_m.is_some() {
            return Err(c.err(
                "preview",
                "texture_size_m",
                "a texture size without a texture",
                "add texture = \"fabric.png\" (an image of the fabric), or remove texture_size_m",
            ));
        }
        return Ok(None);
    };
    let base = c.path.parent().unwrap_or(std::path::Path::new("."));
    let path = base.join(name);
    let pixels = image::ImageReader::open(&path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| e.to_string())
        .and_then(|r| match r.format() {
            Some(image::ImageFormat::Png) => r.into_dimensions().map_err(|e| e.to_string()),
            _ => Err("it is not a PNG image".to_string()),
        })
        .map_err(|e| {
            c.err(
                "preview",
                "texture",
                format!("cannot read {}: {e}", path.display()),
                "give the path of a PNG image of the fabric, relative to the scene file",
            )
        })?;
    let Some(size) = p.texture_size_m else {
        return Err(c.err(
            "preview",
            "texture_size_m",
            "missing: the texture needs the size one copy of the image covers on the fabric",
            "add texture_size_m = [width, height] in m, e.g. [0.1, 0.1] for a 10 cm repeat",
        ));
    };
    let mut size_m = [0.0f32; 2];
    for (k, v) in size.iter().enumerate() {
        size_m[k] = c.within("preview", "texture_size_m", *v, (1e-3, 10.0), "m")?;
    }
    Ok(Some(TextureSetting {
        path,
        size_m,
        pixels,
    }))
}
