//! Building the collision body from the scene's `[body]` settings: mesh, SDF (baked or cached,
//! under the memory cap), exact BVH and contact strategy.

use crate::body::bvh::BodyBvh;
use crate::body::deformed_sdf::DeformedGrid;
use crate::body::edges::BodyEdges;
use crate::body::exact::ExactBody;
use crate::body::sdf::{grid_bytes, grid_for, Sdf};
use crate::body::{shapes, Body, Collider, DeformedBody};
use crate::check::Checker;
use crate::error::InputError;
use crate::scene::{BodySettings, BodySource};
use std::path::PathBuf;

/// Sphere/capsule resolution: rings of latitude, fine enough that the facets sit within
/// 0.5% of the radius (cos(π/48) ≈ 0.9979).
const SHAPE_RINGS: u32 = 48;

/// The body's triangles, checked (`table` names it in errors).
pub fn build_body(settings: &BodySettings, c: &Checker, table: &str) -> Result<Body, InputError> {
    if settings.deform.is_some() {
        return super::deforming::build_deforming(settings, c, table).map(|(body, _)| body);
    }
    let mesh = match &settings.source {
        BodySource::Mesh {
            path,
            scale,
            offset,
        } => return Body::load(path, *scale, *offset, &format!("{table}.path")),
        BodySource::Sphere { center, radius } => shapes::sphere(*center, *radius, SHAPE_RINGS),
        BodySource::Cuboid { center, half } => shapes::cuboid(*center, *half),
        BodySource::Mannequin { feet } => shapes::mannequin(*feet),
        BodySource::Skinned { .. } => {
            return super::deforming::build_deforming(settings, c, table).map(|(body, _)| body)
        }
        BodySource::Capsule {
            center,
            radius,
            half_height,
        } => shapes::capsule(*center, *radius, *half_height, SHAPE_RINGS),
    };
    Body::from_mesh(mesh).map_err(|e| {
        c.err(
            table,
            "shape",
            format!("generated an invalid mesh: {e}"),
            "report this as a bug",
        )
    })
}

/// "if the mesh was modelled in cm, …; otherwise " when a mesh body's size suggests a wrong
/// `units`, else nothing: an SDF too large for memory is the first thing such a body meets.
pub(crate) fn unit_hint(body: &Body, settings: &BodySettings) -> String {
    let BodySource::Mesh { scale, .. } = &settings.source else {
        return String::new();
    };
    let extent = crate::body::size::largest_extent(&body.mesh.positions);
    match crate::body::size::size_problem(extent, *scale) {
        Some((problem, fix)) => format!("{problem}; {fix}. Otherwise "),
        None => String::new(),
    }
}

/// Loads the body (table `table` of the scene), bakes (or reads) its SDF under the memory cap,
/// and builds the collider.
pub(crate) fn build_collider(
    settings: &BodySettings,
    c: &Checker,
    table: &str,
) -> Result<Collider, InputError> {
    let (body, deformation) = super::deforming::build_deforming(settings, c, table)?;
    let (_, dims) = grid_for(&body, settings.sdf_resolution, settings.sdf_margin);
    let bytes = grid_bytes(dims);
    if bytes > settings.sdf_max_bytes {
        // Memory falls with the cube of the spacing.
        let suggested = (settings.sdf_resolution
            * (bytes as f32 / settings.sdf_max_bytes as f32).cbrt()
            * 1.05)
            .min(crate::scene::MAX_SDF_RESOLUTION_M as f32);
        return Err(c.err(
            table,
            "sdf_resolution_m",
            format!(
                "an SDF at {} m needs {dims:?} nodes = {:.0} MiB, above sdf_max_mb = {:.0}",
                settings.sdf_resolution,
                bytes as f64 / 1048576.0,
                settings.sdf_max_bytes as f64 / 1048576.0
            ),
            format!(
                "{}use sdf_resolution_m = {suggested:.4} or coarser, or raise sdf_max_mb",
                unit_hint(&body, settings)
            ),
        ));
    }
    let cache = settings.sdf_cache.then(cache_dir).flatten();
    let (mut sdf, bake) = Sdf::bake_cached(
        &body,
        settings.sdf_resolution,
        settings.sdf_margin,
        cache.as_deref(),
    )
    .map_err(|e| {
        c.err(
            table,
            "",
            format!("cannot bake the SDF: {e}"),
            "check the body mesh",
        )
    })?;
    let exact = ExactBody::new(&body.mesh).map_err(|e| {
        c.err(
            table,
            "",
            format!("cannot build the BVH: {e}"),
            "check the body mesh",
        )
    })?;
    let bvh = settings
        .strategy
        .volume()
        .map(|kind| BodyBvh::new(&body.mesh, kind));
    let deformed = match deformation {
        None => None,
        Some(d) => {
            // A part's box reaches as far as the SDF's margin, plus 2 cm for the skin's
            // blend near joints (a rest point there may map back off its part's own vertices).
            let reach = settings.sdf_margin + 0.02;
            let grid = DeformedGrid::build(
                &body.mesh,
                &d.part_influences,
                d.part_count(),
                &sdf,
                reach,
                cache.as_deref(),
            )
            .map_err(|e| {
                c.err(
                    table,
                    "",
                    format!("cannot bake the nearest triangles: {e}"),
                    "check the body mesh",
                )
            })?;
            sdf.values.extend_from_slice(&grid.words);
            Some(DeformedBody {
                deformation: d,
                parts: grid.parts,
            })
        }
    };
    Ok(Collider {
        deformed,
        bvh,
        edges: settings.edge_contacts.then(|| BodyEdges::new(&body.mesh)),
        body,
        sdf,
        exact,
        motion: settings.motion.clone(),
        strategy: settings.strategy,
        bake,
    })
}

/// `$XDG_CACHE_HOME/drapekit`, else `$HOME/.cache/drapekit`.
fn cache_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("drapekit"))
}
