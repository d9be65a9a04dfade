// Frame health, once per output frame: per workgroup, the kinetic energy ½m|v|² of its free
// particles, their gravitational energy −m·g·x and their springs' elastic energy ½k(l − L)²
// (halved again: each spring is seen from both ends), their largest speed, the largest strain of their springs (and which particle has
// it), and how many have a non-finite position or velocity (and the first). The host finishes
// the reduction over workgroups, so only 32 bytes per 64 particles are read back.
// CPU twin: src/cpu/monitor.rs, which reduces each block of 64 in the same tree order.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var vel: texture_2d<f32>;
@group(0) @binding(3) var spring_offsets: texture_2d<u32>;    // r32uint, N + 1 entries
@group(0) @binding(4) var springs: texture_2d<u32>;           // one SpringRef per texel
// Two entries per workgroup: (kinetic energy, speed, strain, worst particle) as bits, then
// (non-finite count, first non-finite particle, gravitational energy, elastic energy).
@group(0) @binding(5) var<storage, read_write> partials: array<vec4<u32>>;

var<workgroup> energy: array<f32, WORKGROUP_SIZE>;
var<workgroup> gravity_energy: array<f32, WORKGROUP_SIZE>;
var<workgroup> elastic_energy: array<f32, WORKGROUP_SIZE>;
var<workgroup> speed: array<f32, WORKGROUP_SIZE>;
var<workgroup> strain: array<f32, WORKGROUP_SIZE>;
var<workgroup> worst: array<u32, WORKGROUP_SIZE>;
var<workgroup> bad: array<u32, WORKGROUP_SIZE>;
var<workgroup> first_bad: array<u32, WORKGROUP_SIZE>;

// By the bits: an all-ones exponent is an infinity or a NaN (WGSL may fold isnan-style
// comparisons away, so the test is on the representation).
fn finite3(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = particle_index(gid, groups);
    var e = 0.0;
    var eg = 0.0;
    var ee = 0.0;
    var s = 0.0;
    var worst_strain = -1.0;
    var b = 0u;
    var first = 0xffffffffu;
    if (i < params.num_particles) {
        let p = textureLoad(pos, texel(i), 0);
        let v = textureLoad(vel, texel(i), 0).xyz;
        if (!(finite3(p.xyz) && finite3(v))) {
            b = 1u;
            first = i;
        } else {
            if (p.w > 0.0) {
                e = 0.5 * dot(v, v) / p.w;
                eg = -dot(params.gravity.xyz, p.xyz) / p.w;
            }
            s = length(v);
            let begin = textureLoad(spring_offsets, texel(i), 0).x;
            let end = textureLoad(spring_offsets, texel(i + 1u), 0).x;
            for (var k = begin; k < end; k = k + 1u) {
                let sp = unpack_spring(textureLoad(springs, texel(k), 0));
                let q = textureLoad(pos, texel(sp.other), 0).xyz;
                // A non-finite neighbour is counted where it lies, not here.
                if (finite3(q)) {
                    let stretch = length(q - p.xyz) - sp.rest_length;
                    worst_strain = max(worst_strain, stretch / sp.rest_length);
                    ee = ee + 0.25 * sp.stiffness * stretch * stretch;
                }
            }
        }
    }
    energy[local] = e;
    gravity_energy[local] = eg;
    elastic_energy[local] = ee;
    speed[local] = s;
    strain[local] = worst_strain;
    worst[local] = i;
    bad[local] = b;
    first_bad[local] = first;
    workgroupBarrier();
    for (var half = WORKGROUP_SIZE / 2u; half > 0u; half = half / 2u) {
        if (local < half) {
            let o = local + half;
            energy[local] = energy[local] + energy[o];
            gravity_energy[local] = gravity_energy[local] + gravity_energy[o];
            elastic_energy[local] = elastic_energy[local] + elastic_energy[o];
            speed[local] = max(speed[local], speed[o]);
            // Ties keep this slot's candidate: the CPU twin reduces in the same tree.
            if (strain[o] > strain[local]) {
                strain[local] = strain[o];
                worst[local] = worst[o];
            }
            bad[local] = bad[local] + bad[o];
            first_bad[local] = min(first_bad[local], first_bad[o]);
        }
        workgroupBarrier();
    }
    if (local == 0u) {
        let group = i / WORKGROUP_SIZE;
        partials[2u * group] = vec4<u32>(
            bitcast<u32>(energy[0]), bitcast<u32>(speed[0]), bitcast<u32>(strain[0]), worst[0]);
        partials[2u * group + 1u] = vec4<u32>(
            bad[0], first_bad[0], bitcast<u32>(gravity_energy[0]), bitcast<u32>(elastic_energy[0]));
    }
}
