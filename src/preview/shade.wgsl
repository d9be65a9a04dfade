// Preview shading: smooth normals, both sides of the cloth lit (the back face a little darker),
// a key and a fill light and a sky/ground ambient term, darkened by each side's ambient
// occlusion; optionally a checker from the pattern coordinates (uv.xy in m, squares uv.z m
// wide) that shows grain and distortion, or an image of the fabric tiled over them with its
// top towards the panel's +y. Colours are linear; the target is sRGB.

// Keep in sync with `View` in render.rs.
struct View {
    view_proj: mat4x4<f32>,
    // 1 / the fabric image's width and height in m.
    texture_scale: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var fabric: texture_2d<f32>;
@group(0) @binding(2) var fabric_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec3<f32>,
    @location(2) uv: vec3<f32>,
    // Unoccluded ambient on the normal's side and the other; 1 where the image covers it.
    @location(3) shade: vec3<f32>,
}

@vertex
fn vs(
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) uv: vec3<f32>,
    @location(4) shade: vec3<f32>,
) -> VsOut {
    var out: VsOut;
    out.clip = view.view_proj * vec4<f32>(pos, 1.0);
    out.normal = normal;
    out.color = color;
    out.uv = uv;
    out.shade = shade;
    return out;
}

@fragment
fn fs(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    var n = in.normal;
    let len = length(n);
    if (len > 0.0) {
        n = n / len;
    }
    // Sampled outside any branch: implicit derivatives need uniform control flow. glTF and
    // wgpu count t down the image, so the panel's +y is −t.
    let image = textureSample(fabric, fabric_sampler, vec2<f32>(in.uv.x, -in.uv.y) * view.texture_scale.xy).rgb;
    var base = mix(in.color, in.color * image, in.shade.z);
    if (in.uv.z > 0.0) {
        let cell = floor(in.uv.xy / in.uv.z);
        // Alternate squares 30% darker.
        if (fract(0.5 * (cell.x + cell.y)) > 0.25) {
            base = base * 0.7;
        }
    }
    var open = in.shade.x;
    if (!front) {
        n = -n;
        base = base * 0.8;
        open = in.shade.y;
    }
    let key = normalize(vec3<f32>(-0.45, 0.75, 0.6));
    let fill = normalize(vec3<f32>(0.7, 0.2, 0.45));
    // Occlusion darkens the ambient and fill light fully and the key light by half: a fold's
    // inside is in its own shadow, but the key light still models its shape.
    let ambient = (0.22 + 0.08 * n.y) * open;
    let diffuse = 0.68 * max(dot(n, key), 0.0) * (0.5 + 0.5 * open) + 0.22 * max(dot(n, fill), 0.0) * open;
    return vec4<f32>(base * (ambient + diffuse), 1.0);
}
