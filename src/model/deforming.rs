//! Building a deforming body from the scene's `[body]` settings: a skinned glTF avatar (or the
//! shipped rigged mannequin) playing one of its animations, or an OBJ body moved by a vertex
//! cache with rigid parts fitted to it.

use crate::body::cache::{read_cache, read_obj_raw};
use crate::body::deform::{Deformation, Timeline, MAX_MOTION_S};
use crate::body::fit::fit_parts;
use crate::body::gltf_read::{parse_skinned, read_skinned};
use crate::body::Body;
use crate::check::Checker;
use crate::error::InputError;
use crate::scene::{BodySettings, BodySource, DeformMotion};
use std::path::Path;

/// The shipped rigged mannequin, as `examples/rig_mannequin` writes it.
const MANNEQUIN_GLB: &[u8] = include_bytes!("../../fixtures/bodies/mannequin_rigged.glb");

/// Where the shipped rigged mannequin lives in the repository (for messages and summaries).
pub const MANNEQUIN_GLB_PATH: &str = "fixtures/bodies/mannequin_rigged.glb";

/// The body in its rest pose and, when it deforms, its deformation (`table` names it in
/// errors).
pub fn build_deforming(
    settings: &BodySettings,
    c: &Checker,
    table: &str,
) -> Result<(Body, Option<Deformation>), InputError> {
    let Some(deform) = &settings.deform else {
        return super::collider::build_body(settings, c, table).map(|b| (b, None));
    };
    let timeline = Timeline {
        start: deform.start,
        transition: deform.transition,
        plays: deform.plays,
    };
    let closed = |mesh, path: &Path| {
        Body::from_mesh(mesh).map_err(|problem| {
            InputError::new(
                path,
                format!("{table}.path"),
                format!("cannot be used as a collision body: {problem}"),
                "close the mesh (every edge shared by exactly two faces) in a mesh editor",
            )
        })
    };
    match (&settings.source, &deform.motion) {
        (
            BodySource::Skinned {
                path,
                scale,
                offset,
            },
            DeformMotion::Skin { animation },
        ) => {
            let key = format!("{table}.path");
            let (skinned, file) = match path {
                Some(p) => (read_skinned(p, &key)?, p.display().to_string()),
                None => {
                    let name = Path::new(MANNEQUIN_GLB_PATH);
                    let m = parse_skinned(MANNEQUIN_GLB, None, name, &key)
                        .expect("the shipped mannequin reads back (tested)");
                    (m, format!("the built-in mannequin ({MANNEQUIN_GLB_PATH})"))
                }
            };
            let mut skinned = skinned.placed(*scale, *offset);
            let file_path = path.clone().unwrap_or_else(|| MANNEQUIN_GLB_PATH.into());
            let body = closed(skinned.mesh.clone(), &file_path)?;
            // Orientation repairs reorder corners only: the skin keeps its vertices.
            skinned.mesh.triangles.clone_from(&body.mesh.triangles);
            let names: Vec<&str> = skinned.clips.iter().map(|c| c.name.as_str()).collect();
            let Some(name) = animation else {
                return Err(c.err(
                    table,
                    "animation",
                    format!("a skinned body needs an animation; {file} has {names:?}"),
                    format!("add animation = {:?}", names.first().copied().unwrap_or("")),
                ));
            };
            let Some(clip) = skinned.clips.iter().position(|k| &k.name == name) else {
                return Err(c.err(
                    table,
                    "animation",
                    format!(
                        "{file} has no animation {name:?}{}",
                        crate::suggest::did_you_mean(name, names.iter().copied())
                    ),
                    format!("use one of {names:?}"),
                ));
            };
            let description = format!("animation {name:?} of {file}");
            let k = &skinned.clips[clip];
            too_long(c, table, "animation", &timeline, k.duration() - k.start())?;
            let d = Deformation::skinned(skinned, clip, timeline, description);
            Ok((body, Some(d)))
        }
        (
            BodySource::Mesh {
                path,
                scale,
                offset,
            },
            DeformMotion::Cache {
                path: cache_file,
                fps,
                parts,
            },
        ) => {
            let key = format!("{table}.path");
            let mut mesh = read_obj_raw(path, *scale, &key)?;
            for p in &mut mesh.positions {
                *p += *offset;
            }
            let raw = mesh.positions.len();
            let cache_key = format!("{table}.cache");
            let frames = read_cache(cache_file, *fps, raw, &cache_key)?.placed(*scale, *offset);
            let remap = mesh.weld_map();
            let body = closed(mesh, path)?;
            // Every copy of a welded vertex moves alike in a cache of the same mesh: keep the
            // first.
            let welded = body.mesh.positions.len();
            let mut cache = frames;
            for f in &mut cache.frames {
                let mut out = vec![glam::Vec3::ZERO; welded];
                for (old, &new) in remap.iter().enumerate().rev() {
                    out[new as usize] = f[old];
                }
                *f = out;
            }
            let fit = fit_parts(
                &body.mesh.positions,
                &body.mesh.triangles,
                &cache.frames,
                *parts as usize,
            );
            too_long(c, table, "cache", &timeline, cache.duration())?;
            let description = format!(
                "vertex cache {} at {fps} frames/s ({} frames)",
                cache_file.display(),
                cache.frames.len()
            );
            let d = Deformation::cached(
                body.mesh.positions.clone(),
                cache,
                fit,
                timeline,
                description,
            );
            Ok((body, Some(d)))
        }
        _ => Err(c.err(
            table,
            "",
            "this body's source and motion do not go together",
            "report this as a bug",
        )),
    }
}

/// Refuses a motion whose timeline (its transition and `plays` plays of `length` s) is longer
/// than `MAX_MOTION_S`, naming `table`.`key`.
fn too_long(
    c: &Checker,
    table: &str,
    key: &str,
    timeline: &Timeline,
    length: f32,
) -> Result<(), InputError> {
    timeline.fits(length).map_err(|total| {
        c.err(
            table,
            key,
            format!(
                "the motion lasts {total:.3e} s ({} play(s) of {length:.3e} s after a {} s \
                 transition), longer than the {MAX_MOTION_S} s drapekit keys a body's motion over",
                timeline.plays, timeline.transition
            ),
            "check the motion's timing (a cache's fps and its file's sample rate), or play it \
             fewer times (plays)",
        )
    })
}
