//! Previews: the renderer draws what the camera predicts, strain colours measure stretch, and a
//! CPU-backend run can be previewed from the command line.

mod common;

use drapekit::preview::{render, triangle_strain, CameraPreset, DrawMesh};
use glam::{Vec3, Vec4Swizzles};

/// A 1 m × 0.6 m sheet in the xy plane at z = 0, 20 × 12 quads.
fn sheet(color: Vec3) -> DrawMesh {
    let (nx, ny) = (21u32, 13u32);
    let mut m = DrawMesh::default();
    for j in 0..ny {
        for i in 0..nx {
            m.positions.push(Vec3::new(
                i as f32 / (nx - 1) as f32 - 0.5,
                0.6 * j as f32 / (ny - 1) as f32 + 1.0,
                0.0,
            ));
            m.colors.push(color);
        }
    }
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let a = j * nx + i;
            m.triangles.push([a, a + 1, a + nx + 1]);
            m.triangles.push([a, a + nx + 1, a + nx]);
        }
    }
    m
}

#[test]
fn the_sheet_covers_the_rectangle_its_corners_project_to() {
    let Some(ctx) = common::gpu() else { return };
    let red = Vec3::new(0.9, 0.05, 0.05);
    let mesh = sheet(red);
    let (w, h) = (320u32, 240u32);
    let (lo, hi) = (Vec3::new(-0.5, 1.0, 0.0), Vec3::new(0.5, 1.6, 0.0));
    let camera = CameraPreset::Front.framing(lo, hi, w as f32 / h as f32);
    let pixels = render(ctx, &[mesh], &camera, w, h).unwrap();
    assert_eq!(pixels.len(), (4 * w * h) as usize);
    // Where the corners land in pixels (y down).
    let vp = camera.view_proj(w as f32 / h as f32);
    let to_px = |p: Vec3| {
        let c = vp * p.extend(1.0);
        let ndc = c.xyz() / c.w;
        (
            (ndc.x + 1.0) * 0.5 * w as f32,
            (1.0 - ndc.y) * 0.5 * h as f32,
        )
    };
    let (x0, y1) = to_px(lo);
    let (x1, y0) = to_px(hi);
    // A pixel is the sheet's when red dominates (the background is grey, the sheet lit red).
    let is_sheet = |x: u32, y: u32| {
        let k = 4 * (y * w + x) as usize;
        let (r, g, b) = (pixels[k] as i32, pixels[k + 1] as i32, pixels[k + 2] as i32);
        r > g + 40 && r > b + 40
    };
    let (mut inside, mut inside_hit, mut outside_hit) = (0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
            // One pixel of slack at the edges, where the 2×2 supersampling blends.
            let strictly_in = fx > x0 + 1.0 && fx < x1 - 1.0 && fy > y0 + 1.0 && fy < y1 - 1.0;
            let strictly_out = fx < x0 - 1.0 || fx > x1 + 1.0 || fy < y0 - 1.0 || fy > y1 + 1.0;
            if strictly_in {
                inside += 1;
                inside_hit += is_sheet(x, y) as u32;
            } else if strictly_out {
                outside_hit += is_sheet(x, y) as u32;
            }
        }
    }
    assert!(inside > 1000, "the sheet projects to {inside} pixels");
    assert_eq!(
        inside_hit, inside,
        "sheet pixels missing inside its rectangle"
    );
    assert_eq!(outside_hit, 0, "sheet pixels outside its rectangle");
}

#[test]
fn strain_of_a_stretched_sheet_is_its_stretch() {
    let rest = sheet(Vec3::ONE);
    // 10% along x, 0% along y: the largest principal stretch is 1.1.
    let now: Vec<Vec3> = rest
        .positions
        .iter()
        .map(|p| Vec3::new(1.1 * p.x, p.y, p.z))
        .collect();
    let s = triangle_strain(&rest.positions, &now, &rest.triangles);
    for v in s {
        // One f32 rounding of O(1) coordinates per edge: ~1e-7 relative; 1e-5 is ample.
        assert!((v - 0.1).abs() < 1e-5, "{v}");
    }
    // A rigid rotation has no strain.
    let r = glam::Quat::from_rotation_y(0.7);
    let turned: Vec<Vec3> = rest.positions.iter().map(|p| r * *p).collect();
    for v in triangle_strain(&rest.positions, &turned, &rest.triangles) {
        assert!(v.abs() < 1e-5, "{v}");
    }
}

#[test]
fn a_cpu_run_can_be_previewed() {
    // The CPU backend runs; the preview makes its own device (the fallback adapter here).
    if common::gpu().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("drapekit-preview-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let bin = env!("CARGO_BIN_EXE_drapekit");
    let run = std::process::Command::new(bin)
        .args([
            "run",
            common::fixture("scenes/drape_sphere.toml")
                .to_str()
                .unwrap(),
        ])
        .args([
            "--backend",
            "cpu",
            "--frames",
            "6",
            "--out",
            dir.join("run").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let png = dir.join("p.png");
    let out = std::process::Command::new(bin)
        .args([
            "preview",
            dir.join("run").to_str().unwrap(),
            "--adapter",
            "fallback",
        ])
        .args([
            "--size",
            "200x150",
            "--mode",
            "strain",
            "--out",
            png.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    // PNG signature, then the IHDR chunk's width and height.
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 200);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 150);
    // A frame that is not there is bad input, exit 2.
    let missing = std::process::Command::new(bin)
        .args([
            "preview",
            dir.join("run").to_str().unwrap(),
            "--frame",
            "999",
        ])
        .args(["--out", dir.join("q.png").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("has no frame 999"));
    let _ = std::fs::remove_dir_all(&dir);
}
