// Preview shading: smooth normals, both sides of the cloth lit (the back face a little darker),
// a key and a fill light and a sky/ground ambient term; optionally a checker from the pattern
// coordinates (uv.xy in m, squares uv.z m wide) that shows grain and distortion. Colours are
// linear; the target is sRGB.

struct View {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec3<f32>,
    @location(2) uv: vec3<f32>,
}

@vertex
fn vs(
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) uv: vec3<f32>,
) -> VsOut {
    var out: VsOut;
    out.clip = view.view_proj * vec4<f32>(pos, 1.0);
    out.normal = normal;
    out.color = color;
    out.uv = uv;
    return out;
}

@fragment
fn fs(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    var n = in.normal;
    let len = length(n);
    if (len > 0.0) {
        n = n / len;
    }
    var base = in.color;
    if (in.uv.z > 0.0) {
        let cell = floor(in.uv.xy / in.uv.z);
        // Alternate squares 30% darker.
        if (fract(0.5 * (cell.x + cell.y)) > 0.25) {
            base = base * 0.7;
        }
    }
    if (!front) {
        n = -n;
        base = base * 0.8;
    }
    let key = normalize(vec3<f32>(-0.45, 0.75, 0.6));
    let fill = normalize(vec3<f32>(0.7, 0.2, 0.45));
    let ambient = 0.22 + 0.08 * n.y;
    let light = ambient + 0.68 * max(dot(n, key), 0.0) + 0.22 * max(dot(n, fill), 0.0);
    return vec4<f32>(base * light, 1.0);
}
