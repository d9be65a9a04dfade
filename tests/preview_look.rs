//! The designer's look of previews: ambient occlusion reaches the pixels, a fabric image lies
//! over the pattern coordinates with its top towards each panel's +y, each preset has its
//! colour and strain range, a turntable goes round, and a fixed textured scene renders as its
//! golden image.

mod common;

use drapekit::preview::{
    ambient_occlusion, render_textured, scene_look, srgb_byte, CameraPreset, ColorMode, DrawMesh,
    FabricTexture, Previewer, TURNTABLE_STEPS,
};
use drapekit::scene::Scene;
use glam::{Vec2, Vec3, Vec4Swizzles};

/// The front camera's lighting of a surface facing it (+z), as `shade.wgsl` computes it, with
/// `open` of its ambient light unoccluded: ambient (0.22 + 0.08·n.y)·open, key
/// 0.68·(n·key)·(0.5 + 0.5·open), fill 0.22·(n·fill)·open.
fn facing_light(open: f32) -> f32 {
    let key = Vec3::new(-0.45, 0.75, 0.6).normalize();
    let fill = Vec3::new(0.7, 0.2, 0.45).normalize();
    0.22 * open + 0.68 * key.z * (0.5 + 0.5 * open) + 0.22 * fill.z * open
}

/// The sheet (1 m × 0.6 m at z = 0, y from 1 to 1.6) with pattern coordinates u = x + 0.5,
/// v = y − 1 in m, rendered from the front at 200 × 150, and a function from a point on it to
/// its pixel.
fn render_sheet(
    sheet: &DrawMesh,
    texture: Option<&FabricTexture>,
) -> (Vec<u8>, impl Fn(&[u8], Vec3) -> [u8; 3]) {
    let ctx = common::gpu().expect("checked by the caller");
    let (w, h) = (200u32, 150u32);
    let camera = CameraPreset::Front.framing(
        Vec3::new(-0.5, 1.0, 0.0),
        Vec3::new(0.5, 1.6, 0.0),
        w as f32 / h as f32,
    );
    let pixels = render_textured(ctx, std::slice::from_ref(sheet), texture, &camera, w, h).unwrap();
    let vp = camera.view_proj(w as f32 / h as f32);
    let at = move |pixels: &[u8], p: Vec3| {
        let c = vp * p.extend(1.0);
        let ndc = c.xyz() / c.w;
        let (x, y) = (
            ((ndc.x + 1.0) * 0.5 * w as f32) as u32,
            ((1.0 - ndc.y) * 0.5 * h as f32) as u32,
        );
        let k = 4 * (y * w + x) as usize;
        [pixels[k], pixels[k + 1], pixels[k + 2]]
    };
    (pixels, at)
}

/// The GPU lights in f32 and rounds sRGB its own way; a flat region averages four equal
/// samples: 3 of 255 covers both (as in preview_colors.rs).
fn assert_close(got: [u8; 3], want: Vec3, what: &str) {
    let want = want.to_array().map(srgb_byte);
    for c in 0..3 {
        assert!(
            (got[c] as i32 - want[c] as i32).abs() <= 3,
            "{what}: rendered {got:?}, expected {want:?}"
        );
    }
}

#[test]
fn occlusion_darkens_the_ambient_light_as_the_shader_says() {
    if common::gpu().is_none() {
        return;
    }
    // The left half of the sheet a quarter open, the right half fully: the shader's formula.
    let mut sheet = common::sheet(Vec3::splat(0.6));
    sheet.occlusion = (sheet.positions.iter())
        .map(|p| if p.x < 0.0 { [0.25, 1.0] } else { [1.0, 1.0] })
        .collect();
    let (pixels, at) = render_sheet(&sheet, None);
    assert_close(
        at(&pixels, Vec3::new(-0.3, 1.3, 0.0)),
        Vec3::splat(0.6 * facing_light(0.25)),
        "occluded",
    );
    assert_close(
        at(&pixels, Vec3::new(0.3, 1.3, 0.0)),
        Vec3::splat(0.6 * facing_light(1.0)),
        "open",
    );
    // And the occlusion of a real fold: two sheets 2 cm apart darken each other's inner side.
    let a = common::sheet(Vec3::ONE);
    let mut b = a.clone();
    for p in &mut b.positions {
        p.z = -0.02;
    }
    let open = ambient_occlusion(&[a, b]);
    let mid = open[0].len() / 2;
    // The first sheet's normal is +z (away from the second): its back side faces it.
    assert!(
        open[0][mid][1] < 0.3 && open[0][mid][0] == 1.0,
        "{:?}",
        open[0][mid]
    );
}

#[test]
fn a_fabric_image_lies_over_the_pattern_with_its_top_towards_the_panels_plus_y() {
    if common::gpu().is_none() {
        return;
    }
    // An 8 × 8 image: the top four rows red, the bottom four blue, one copy per 0.2 m × 0.2 m.
    let red = image::Rgba([200, 30, 30, 255]);
    let blue = image::Rgba([30, 30, 200, 255]);
    let image = image::RgbaImage::from_fn(8, 8, |_, y| if y < 4 { red } else { blue });
    let texture = FabricTexture {
        image,
        size_m: [0.2, 0.2],
    };
    let mut sheet = common::sheet(Vec3::ONE);
    sheet.uv = (sheet.positions.iter())
        .map(|p| Vec2::new(p.x + 0.5, p.y - 1.0))
        .collect();
    sheet.textured = true;
    let (pixels, at) = render_sheet(&sheet, Some(&texture));
    // Each copy spans v in [0.2k, 0.2k + 0.2]: its upper half (v from 0.1 to 0.2 into it) is
    // the image's top half. Sampled a quarter of a copy from its top and from its bottom, two
    // texels from any change of colour: the image is magnified (a texel is 25 mm, a pixel
    // 6 mm), so the linear filter returns the colour there exactly.
    let linear = |c: image::Rgba<u8>| {
        Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32).map(|v| {
            let v = v / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        })
    };
    for (v, color, what) in [(0.35, red, "upper half"), (0.25, blue, "lower half")] {
        let got = at(&pixels, Vec3::new(0.05, 1.0 + v, 0.0));
        assert_close(got, linear(color) * facing_light(1.0), what);
    }
}

#[test]
fn each_preset_has_its_colour_and_strain_range_and_the_scene_overrides_them() {
    let path = common::fixture("scenes/tshirt_drape_cotton.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let look =
        |text: &str| scene_look(Some(&Scene::parse(text, &path).unwrap()), ColorMode::Fabric);
    let cotton = look(&text);
    let cotton_color = drapekit::scene::hex_color("#a9c1dc").unwrap();
    assert_eq!(cotton.colors, [cotton_color]);
    // Wovens work within 5% strain; the knit within 20%.
    assert_eq!(cotton.strain_max, 0.05);
    assert!(cotton.occlusion);
    let jersey = look(&text.replace("preset = \"cotton\"", "preset = \"jersey\""));
    assert_eq!(jersey.strain_max, 0.2);
    assert_ne!(jersey.colors, cotton.colors);
    let given = look(&text.replace(
        "camera = \"front\"",
        "camera = \"front\"\nstrain_max = 0.1\ncolors = [\"#ff0000\"]",
    ));
    assert_eq!(given.strain_max, 0.1);
    assert_eq!(given.colors, [Vec3::new(1.0, 0.0, 0.0)]);
    // Strain colours stay exact: no occlusion there.
    let strain = scene_look(
        Some(&Scene::parse(&text, &path).unwrap()),
        ColorMode::Strain,
    );
    assert!(!strain.occlusion);
}

#[test]
fn a_turntable_goes_all_the_way_round() {
    if common::gpu().is_none() {
        return;
    }
    // A frame of the sheet, bent so that front and back differ, spun in 36 steps.
    let dir = std::env::temp_dir().join(format!("drapekit-turntable-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut text = String::new();
    let sheet = common::sheet(Vec3::ONE);
    for p in &sheet.positions {
        text += &format!("v {} {} {}\n", p.x, p.y, 0.3 * p.x * p.x);
    }
    for t in &sheet.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(dir.join("frame_0000.obj"), text).unwrap();
    let mut previewer = Previewer::new(&dir, None, 24.0, &common::test_adapter()).unwrap();
    let mut look = scene_look(None, ColorMode::Fabric);
    look.size = (64, 48);
    let gif = dir.join("spin.gif");
    let steps = drapekit::preview::write_turntable(&mut previewer, None, &look, &gif).unwrap();
    assert_eq!(steps, TURNTABLE_STEPS as usize);
    use image::AnimationDecoder;
    let file = std::io::BufReader::new(std::fs::File::open(&gif).unwrap());
    let frames = image::codecs::gif::GifDecoder::new(file)
        .unwrap()
        .into_frames()
        .collect_frames()
        .unwrap();
    assert_eq!(frames.len(), 36);
    // 3.6 s a turn (GIF delays are in hundredths of a second); the half-turn view differs from
    // the first, more than the last step's, one step short of the full turn.
    assert_eq!(frames[0].delay().numer_denom_ms(), (100, 1));
    let differ = |a: &image::Frame, b: &image::Frame| {
        (a.buffer().pixels().zip(b.buffer().pixels()))
            .filter(|(p, q)| (0..3).any(|c| (p[c] as i32 - q[c] as i32).abs() > 8))
            .count()
    };
    assert!(
        differ(&frames[0], &frames[18]) > 100,
        "the back is not the front"
    );
    assert!(differ(&frames[0], &frames[35]) < differ(&frames[0], &frames[18]));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_fixed_textured_scene_renders_as_its_golden_image() {
    let Some(ctx) = common::gpu() else { return };
    // A sheet curved into a half-pipe around a sphere 3 cm from its inside, in the shipped
    // gingham (4 cm repeat) over its pattern coordinates, the two occluding each other;
    // three-quarter view into the pipe.
    let (w, h) = (160u32, 120u32);
    let mut sheet = common::sheet(Vec3::ONE);
    sheet.uv = (sheet.positions.iter())
        .map(|p| Vec2::new(p.x + 0.5, p.y - 1.0))
        .collect();
    for p in &mut sheet.positions {
        p.z = -0.3 * (1.0 - 4.0 * p.x * p.x);
    }
    sheet.textured = true;
    let mut sphere = DrawMesh::default();
    let (rings, segments) = (12u32, 18u32);
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            sphere.positions.push(Vec3::new(0.0, 1.3, -0.02) + 0.25 * d);
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
    let mut meshes = vec![sheet, sphere];
    let open = ambient_occlusion(&meshes);
    for (m, open) in meshes.iter_mut().zip(open) {
        m.occlusion = open;
    }
    let setting = drapekit::scene::TextureSetting {
        path: common::fixture("textures/gingham.png"),
        size_m: [0.04, 0.04],
        pixels: (64, 64),
    };
    let texture = FabricTexture::load(&setting).unwrap();
    let camera = CameraPreset::ThreeQuarter.framing(
        Vec3::new(-0.5, 1.0, -0.3),
        Vec3::new(0.5, 1.6, 0.3),
        w as f32 / h as f32,
    );
    let pixels = render_textured(ctx, &meshes, Some(&texture), &camera, w, h).unwrap();
    common::assert_golden(
        &pixels,
        (w, h),
        "golden/halfpipe_sphere_fabric.png",
        "preview_look",
    );
}
