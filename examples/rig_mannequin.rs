//! Rigs the shipped mannequin (joints at landmarks, computed skin weights, the built-in motions)
//! and writes it as `fixtures/bodies/mannequin_rigged.glb`, the file that scenes with
//! `shape = "mannequin"` and an animation read back through the glTF import.
//!
//! ```text
//! cargo run --release --example rig_mannequin                  # rewrite the shipped file
//! cargo run --release --example rig_mannequin -- --sheet a.png # and draw the rig and motions
//! ```
//! The sheet shows the rest pose coloured by joint weights (left) and each motion at a few times.

use drapekit::body::rig::rigged_mannequin;
use drapekit::body::shapes;
use drapekit::body::skin::SkinnedMesh;
use drapekit::gpu::{AdapterChoice, GpuContext};
use drapekit::preview::write_png;
use drapekit::preview::CameraPreset;
use drapekit::preview::{render, DrawMesh};
use glam::Vec3;
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let body = rigged_mannequin();
    let bytes = drapekit::body::gltf_write::skinned_glb(&body, "mannequin")
        .ok_or("the rig does not fit in a glTF file")?;
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bodies/mannequin_rigged.glb");
    drapekit::atomic_file::write_atomic(&out, &bytes)?;
    println!("wrote {} ({} bytes)", out.display(), bytes.len());
    let args: Vec<String> = std::env::args().collect();
    if let Some(k) = args.iter().position(|a| a == "--sheet") {
        let path = args.get(k + 1).ok_or("--sheet needs a file name")?;
        sheet(&body, Path::new(path))?;
        println!("drew {path}");
    }
    Ok(())
}

/// Colours that tell neighbouring joints apart.
fn palette(j: usize) -> Vec3 {
    let hues = [
        [0.8, 0.2, 0.2],
        [0.2, 0.7, 0.2],
        [0.2, 0.3, 0.9],
        [0.9, 0.8, 0.1],
        [0.8, 0.3, 0.8],
        [0.1, 0.8, 0.8],
        [0.95, 0.5, 0.1],
    ];
    Vec3::from(hues[j % hues.len()])
}

fn draw(positions: Vec<Vec3>, body: &SkinnedMesh, colored: bool) -> DrawMesh {
    let colors = if colored {
        (body.influences.iter())
            .map(|inf| {
                (inf.joints.iter().zip(inf.weights))
                    .map(|(j, w)| palette(*j as usize) * w)
                    .sum()
            })
            .collect()
    } else {
        vec![Vec3::new(0.62, 0.60, 0.58); positions.len()]
    };
    DrawMesh {
        positions,
        colors,
        triangles: body.mesh.triangles.clone(),
        ..Default::default()
    }
}

fn sheet(body: &SkinnedMesh, out: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let ctx = GpuContext::new(&AdapterChoice::Fallback)?;
    let (w, h) = (300u32, 460u32);
    let mut tiles: Vec<(String, Vec<DrawMesh>)> = Vec::new();
    let mut rest = vec![draw(body.mesh.positions.clone(), body, true)];
    // The joints as small spheres.
    let globals = body.skeleton.globals(&body.skeleton.rest);
    for g in &globals {
        let at = g.transform_point3(Vec3::ZERO);
        let s = shapes::sphere(at, 0.015, 8);
        rest.push(DrawMesh {
            colors: vec![Vec3::new(0.05, 0.05, 0.05); s.positions.len()],
            positions: s.positions,
            triangles: s.triangles,
            ..Default::default()
        });
    }
    tiles.push(("rest".into(), rest));
    for clip in &body.clips {
        let d = clip.duration();
        for k in 1..=3 {
            let t = d * k as f32 / 3.0;
            let t = if clip.name == "walk" {
                d * k as f32 / 8.0
            } else {
                t
            };
            let locals = clip.pose(&body.skeleton, t);
            tiles.push((
                format!("{} {t:.2}", clip.name),
                vec![draw(body.posed(&locals), body, false)],
            ));
        }
    }
    let cols = 5u32;
    let rows = (tiles.len() as u32).div_ceil(cols);
    let mut pixels = vec![0u8; (rows * cols * w * h * 4) as usize];
    let (lo, hi) = (Vec3::new(-0.6, 0.0, -0.4), Vec3::new(0.6, 1.7, 0.4));
    for (c, (_, meshes)) in tiles.iter().enumerate() {
        let view = if c == 0 {
            CameraPreset::Front
        } else {
            CameraPreset::ThreeQuarter
        };
        let camera = view.framing(lo, hi, w as f32 / h as f32);
        let tile = render(&ctx, meshes, &camera, w, h)?;
        let (tr, tc) = (c as u32 / cols, c as u32 % cols);
        for row in 0..h {
            let src = (row * w * 4) as usize;
            let dst = (((tr * h + row) * cols * w + tc * w) * 4) as usize;
            pixels[dst..dst + (w * 4) as usize].copy_from_slice(&tile[src..src + (w * 4) as usize]);
        }
    }
    write_png(out, &pixels, cols * w, rows * h)?;
    Ok(())
}
