//! Loads a GarmentCode sewing pattern, meshes and places its panels as a run would, and writes
//! them, flat and not yet sewn, as an OBJ with one group per panel (open it in any 3D viewer).
//!
//!     cargo run --release --example pattern_to_obj -- fixtures/patterns/tshirt.json panels.obj

use drapekit::export::obj::{cloth_obj, panel_groups};
use drapekit::pattern::garment::{Garment, GarmentOptions};
use drapekit::pattern::Pattern;
use std::path::PathBuf;

fn main() -> Result<(), drapekit::Error> {
    let mut args = std::env::args().skip(1);
    let pattern_path = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "fixtures/patterns/tshirt.json".into()),
    );
    let out = PathBuf::from(args.next().unwrap_or_else(|| "panels.obj".into()));

    let pattern = Pattern::load(&pattern_path)?;
    let garment = Garment::build(
        &pattern,
        &GarmentOptions {
            particle_distance: 0.02, // m between particles
            placement: Default::default(),
        },
    )?;
    println!(
        "{}: {} panels ({}), {} particles, {} triangles, {} seams of {} vertex pairs",
        pattern_path.display(),
        garment.panel_names.len(),
        garment.panel_names.join(", "),
        garment.mesh.positions.len(),
        garment.mesh.triangles.len(),
        garment.stitches,
        garment.seam_pairs.len(),
    );

    let groups = panel_groups(&garment.panel_names, &garment.triangle_panel);
    let obj = cloth_obj(
        &garment.mesh.positions,
        &garment.mesh.triangles,
        Some(&garment.uv),
        &groups,
    );
    std::fs::write(&out, obj).map_err(|e| drapekit::Error::io(&out, e))?;
    println!("wrote {}", out.display());
    Ok(())
}
