//! Preview colours as pixels: strain and panel colours and the checker come out of the renderer
//! as the colour maps say, the legend shows the map and its labels, and a fixed scene still
//! renders as its golden image.

mod common;

use drapekit::preview::{
    draw_legend, render, srgb_byte, strain_legend, strain_ramp, CameraChoice, CameraPreset,
    ColorMode, DrawMesh, Look, Previewer,
};
use glam::{Vec3, Vec4Swizzles};

/// A temporary run folder holding `frames` as `frame_NNNN.obj` (positions and triangles only).
fn run_folder(name: &str, frames: &[(u32, &DrawMesh)]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("drapekit-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (n, m) in frames {
        let mut text = String::new();
        for p in &m.positions {
            text += &format!("v {} {} {}\n", p.x, p.y, p.z);
        }
        for t in &m.triangles {
            text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        std::fs::write(dir.join(format!("frame_{n:04}.obj")), text).unwrap();
    }
    dir
}

/// The front camera's lighting of a surface facing it (+z), as `shade.wgsl` computes it:
/// ambient 0.22, key 0.68·(n·key), fill 0.22·(n·fill).
fn facing_light() -> f32 {
    let key = Vec3::new(-0.45, 0.75, 0.6).normalize();
    let fill = Vec3::new(0.7, 0.2, 0.45).normalize();
    0.22 + 0.68 * key.z + 0.22 * fill.z
}

#[test]
fn strain_colours_of_a_stretched_sheet_follow_the_colour_map() {
    if common::gpu().is_none() {
        return;
    }
    // The left half stretched 5% along x, the right half 15% (continuous at x = 0): with
    // strain_max 20% the halves sit at a quarter and three quarters of the colour map.
    let rest = common::sheet(Vec3::ONE);
    let mut now = rest.clone();
    for p in &mut now.positions {
        p.x *= if p.x < 0.0 { 1.05 } else { 1.15 };
    }
    let dir = run_folder("strain-map", &[(0, &rest), (1, &now)]);
    let mut previewer = Previewer::new(&dir, None, 24.0, &common::test_adapter()).unwrap();
    let (w, h) = (200u32, 150u32);
    let look = Look {
        camera: CameraChoice::Preset(CameraPreset::Front),
        mode: ColorMode::Strain,
        size: (w, h),
        strain_max: 0.2,
        seams: false,
        legend: false,
        colors: Vec::new(),
        checker: 0.0,
        occlusion: false,
        texture: None,
    };
    let pixels = previewer.image(Some(1), &look, None).unwrap();
    // The sheet spans x in [-0.525, 0.575] at y 1.0..1.6; sample well inside each half.
    let camera = CameraPreset::Front.framing(
        Vec3::new(-0.525, 1.0, 0.0),
        Vec3::new(0.575, 1.6, 0.0),
        w as f32 / h as f32,
    );
    let vp = camera.view_proj(w as f32 / h as f32);
    let pixel_at = |p: Vec3| {
        let c = vp * p.extend(1.0);
        let ndc = c.xyz() / c.w;
        let (x, y) = (
            ((ndc.x + 1.0) * 0.5 * w as f32) as u32,
            ((1.0 - ndc.y) * 0.5 * h as f32) as u32,
        );
        let k = 4 * (y * w + x) as usize;
        [pixels[k], pixels[k + 1], pixels[k + 2]]
    };
    for (x, t) in [(-0.25, 0.25), (0.3, 0.75)] {
        let got = pixel_at(Vec3::new(x, 1.3, 0.0));
        let want = (strain_ramp(t) * facing_light()).to_array().map(srgb_byte);
        // The GPU lights in f32 and encodes sRGB in its own rounding; a flat region then
        // averages four equal samples. 3 of 255 covers both roundings with room to spare,
        // while the map's neighbouring strain of 1% (t ± 0.05) moves a channel by ≥ 10.
        for c in 0..3 {
            assert!(
                (got[c] as i32 - want[c] as i32).abs() <= 3,
                "strain {t}×20% at x = {x}: rendered {got:?}, colour map {want:?}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_legend_shows_the_colour_map_and_its_labels() {
    let (w, h) = (1280u32, 960u32);
    let background = 180u8;
    let mut pixels = vec![background; (4 * w * h) as usize];
    let legend = strain_legend(0.2);
    let b = draw_legend(&mut pixels, w, h, &legend);
    let at = |x: u32, y: u32| {
        let k = 4 * (y * w + x) as usize;
        [pixels[k], pixels[k + 1], pixels[k + 2]]
    };
    // In the top-right corner, and tall enough to read (a third of the image or more).
    assert!(b.panel.2 <= w && b.panel.0 > w / 2 && b.panel.1 < h / 10);
    assert!(b.bar.3 - b.bar.1 >= h / 3);
    // The bar's top row is the map's 20% colour, its bottom row 0%, its middle 10%.
    let mid_x = (b.bar.0 + b.bar.2) / 2;
    let exact = |t: f32| strain_ramp(t).to_array().map(srgb_byte);
    assert_eq!(at(mid_x, b.bar.1), exact(1.0));
    assert_eq!(at(mid_x, b.bar.3 - 1), exact(0.0));
    let middle = at(mid_x, (b.bar.1 + b.bar.3 - 1) / 2);
    for (got, want) in middle.iter().zip(exact(0.5)) {
        // The middle row is within half a row of t = 0.5: a fraction of a level.
        assert!((*got as i32 - want as i32).abs() <= 2);
    }
    // Labels: dark ink right of the bar, in rows near each of the five ticks.
    let ink = |x: u32, y: u32| at(x, y).iter().all(|&v| v < 40);
    for k in 0..5 {
        let y = b.bar.1 + (b.bar.3 - 1 - b.bar.1) * (4 - k) / 4;
        let rows = y.saturating_sub(12)..(y + 12).min(h);
        let found = rows
            .flat_map(|y| (b.bar.2 + 4..b.panel.2).map(move |x| (x, y)))
            .any(|(x, y)| ink(x, y));
        assert!(found, "no label at tick {k}");
    }
    // Nothing is drawn outside the panel.
    let outside = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| x < b.panel.0 || x >= b.panel.2 || y < b.panel.1 || y >= b.panel.3)
        .any(|(x, y)| at(x, y) != [background; 3]);
    assert!(!outside, "the legend drew outside its panel");
    // At 4K the text scales up: the panel grows with the image.
    let (w4, h4) = (3840u32, 2160u32);
    let mut big = vec![background; (4 * w4 * h4) as usize];
    let b4 = draw_legend(&mut big, w4, h4, &legend);
    assert!(b4.panel.3 - b4.panel.1 > 2 * (b.panel.3 - b.panel.1) * 2 / 3);
}

/// The golden image's scene: a sheet curved into a half-pipe, coloured along x by the strain
/// map, in front of a coarse sphere, seen three-quarter, with the strain legend.
fn golden_scene() -> Vec<DrawMesh> {
    let mut sheet = common::sheet(Vec3::ONE);
    for (p, c) in sheet.positions.iter_mut().zip(&mut sheet.colors) {
        *c = strain_ramp(p.x + 0.5);
        p.z = 0.3 * (1.0 - 4.0 * p.x * p.x);
    }
    let mut sphere = DrawMesh::default();
    let (rings, segments) = (8u32, 12u32);
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            sphere.positions.push(Vec3::new(0.0, 1.3, -0.2) + 0.25 * d);
            sphere.colors.push(drapekit::preview::BODY);
        }
    }
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (i * segments + j, i * segments + (j + 1) % segments);
            let (c, d) = (a + segments, b + segments);
            sphere.triangles.push([a, c, b]);
            sphere.triangles.push([b, c, d]);
        }
    }
    vec![sheet, sphere]
}

#[test]
fn a_fixed_scene_renders_as_its_golden_image() {
    let Some(ctx) = common::gpu() else { return };
    let (w, h) = (160u32, 120u32);
    let meshes = golden_scene();
    let camera = CameraPreset::ThreeQuarter.framing(
        Vec3::new(-0.5, 1.0, -0.45),
        Vec3::new(0.5, 1.6, 0.3),
        w as f32 / h as f32,
    );
    let mut pixels = render(ctx, &meshes, &camera, w, h).unwrap();
    draw_legend(&mut pixels, w, h, &strain_legend(0.2));
    common::assert_golden(
        &pixels,
        (w, h),
        "golden/sheet_sphere_strain.png",
        "preview_colors",
    );
}

#[test]
fn fabric_mode_colours_each_panel_and_lays_a_checker_over_the_pattern() {
    if common::gpu().is_none() {
        return;
    }
    // The sheet as two panels (left and right of x = 0) with pattern coordinates u = x + 0.5,
    // v = y − 1 in m, as drapekit writes garment frames.
    let m = common::sheet(Vec3::ONE);
    let mut text = String::new();
    for p in &m.positions {
        text += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for p in &m.positions {
        text += &format!("vt {} {}\n", p.x + 0.5, p.y - 1.0);
    }
    for (name, left) in [("left", true), ("right", false)] {
        text += &format!("g {name}\n");
        for t in &m.triangles {
            let cx: f32 = t.iter().map(|&i| m.positions[i as usize].x).sum();
            if (cx < 0.0) == left {
                let [a, b, c] = t.map(|i| i + 1);
                text += &format!("f {a}/{a} {b}/{b} {c}/{c}\n");
            }
        }
    }
    let dir = std::env::temp_dir().join(format!("drapekit-panels-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("frame_0000.obj"), text).unwrap();
    let frame = drapekit::preview::read_obj(&dir.join("frame_0000.obj")).unwrap();
    assert_eq!(frame.uv.len(), m.positions.len());
    assert_eq!(*frame.groups.iter().max().unwrap(), 1);
    let mut previewer = Previewer::new(&dir, None, 24.0, &common::test_adapter()).unwrap();
    let (w, h) = (200u32, 150u32);
    let look = Look {
        camera: CameraChoice::Preset(CameraPreset::Front),
        mode: ColorMode::Fabric,
        size: (w, h),
        strain_max: 0.2,
        seams: false,
        legend: true,
        colors: Vec::new(),
        checker: 0.1,
        occlusion: false,
        texture: None,
    };
    let pixels = previewer.image(None, &look, None).unwrap();
    let camera = CameraPreset::Front.framing(
        Vec3::new(-0.5, 1.0, 0.0),
        Vec3::new(0.5, 1.6, 0.0),
        4.0 / 3.0,
    );
    let vp = camera.view_proj(w as f32 / h as f32);
    let at = |p: Vec3| {
        let c = vp * p.extend(1.0);
        let (x, y) = (
            ((c.x / c.w + 1.0) * 0.5 * w as f32) as u32,
            ((1.0 - c.y / c.w) * 0.5 * h as f32) as u32,
        );
        let k = 4 * (y * w + x) as usize;
        [pixels[k], pixels[k + 1], pixels[k + 2]]
    };
    // Centres of checker squares (0.1 m): (u, v) cells (1, 3) and (7, 3) are light, (2, 3)
    // dark (alternate squares are 30% darker); the panels take the palette's first two colours.
    let palette = drapekit::preview::PALETTE;
    for (x, color, shade) in [
        (-0.35, palette[0], 1.0),
        (-0.25, palette[0], 0.7),
        (0.25, palette[1], 1.0),
    ] {
        let got = at(Vec3::new(x, 1.35, 0.0));
        let want = (color * shade * facing_light()).to_array().map(srgb_byte);
        // As for the strain colours: the GPU's f32 lighting and sRGB rounding, 3 levels.
        for c in 0..3 {
            assert!(
                (got[c] as i32 - want[c] as i32).abs() <= 3,
                "x = {x}: rendered {got:?}, expected {want:?}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
