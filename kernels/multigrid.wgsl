// One row of each operation on a level's linear system A·e = rhs (the Newton step's
// preconditioner): a block Gauss–Seidel update, the residual, restriction and prolongation.
// Composed (after hierarchy.wgsl and block_texels.wgsl) into smooth, level_residual, restrict and prolong, which run
// one operation over a level's rows per dispatch, and into coarse_cycle, which runs a list of
// them on small levels in one workgroup. Every level's rows are concatenated in rhs, e and res
// (at the level's vec_base); level 0's rhs is conjugate gradients' residual r and its e the
// preconditioned residual z. CPU twins: src/cpu/smooth.rs, restrict.rs, prolong.rs.

@group(0) @binding(24) var<storage, read_write> rhs: array<vec4<f32>>;
@group(0) @binding(25) var<storage, read_write> e: array<vec4<f32>>;
@group(0) @binding(26) var<storage, read_write> res: array<vec4<f32>>;

// How many of a row's blocks an invocation loads at once (pipeline-overridable: 4 with the
// storage-buffer layout, GPUs' default; 1 with textures, software adapters' default; see
// ArrayLayout::blocks_in_flight in src/gpu/array_layout.rs).
override BLOCKS_IN_FLIGHT: u32 = 1u;

// Levels of at most this many rows keep their correction in workgroup memory while
// coarse_cycle smooths them (pipeline-overridable; 0: never, the default of every other kernel).
override CACHE_ROWS: u32 = 0u;
// The correction of the level being smoothed, three floats a row, while `cached` is set.
var<workgroup> e_cache: array<f32, 3u * CACHE_ROWS + 3u>;
var<private> cached: bool = false;

// Row r of the cached correction.
fn cache_load(r: u32) -> vec3<f32> {
    return vec3<f32>(e_cache[3u * r], e_cache[3u * r + 1u], e_cache[3u * r + 2u]);
}

fn cache_store(r: u32, v: vec3<f32>) {
    e_cache[3u * r] = v.x;
    e_cache[3u * r + 1u] = v.y;
    e_cache[3u * r + 2u] = v.z;
}

// Row c's correction on level lv: from workgroup memory while the level is cached.
fn correction(lv: Level, c: u32) -> vec3<f32> {
    if (CACHE_ROWS > 0u && cached) {
        return cache_load(c);
    }
    return e[lv.vec_base + c].xyz;
}

// Block b's product with its column's correction (b: the level's own block index).
fn block_product(lv: Level, b: u32) -> vec3<f32> {
    return block_at(lv.block_base + b) * correction(lv, block_column(lv, b));
}

// `sum` − Σ_b A_b·e_column(b) over a row's blocks first .. end, subtracted one after another in
// the CPU twins' order (the same bits whatever BLOCKS_IN_FLIGHT is). With four blocks in flight
// a step's four products load their blocks, columns and corrections independently of each
// other and of the running sum, so a GPU invocation waits for memory once per four blocks
// instead of once per block: a coarse level's row has dozens of blocks, and a colour takes as
// long as its longest row. Software adapters run invocations in SIMD lanes, where the wait is
// not the cost; they take the blocks one at a time.
fn subtract_row_products(sum0: vec3<f32>, lv: Level, first: u32, end: u32) -> vec3<f32> {
    var sum = sum0;
    var b = first;
    if (BLOCKS_IN_FLIGHT == 4u) {
        for (; b + 4u <= end; b = b + 4u) {
            let x0 = block_product(lv, b);
            let x1 = block_product(lv, b + 1u);
            let x2 = block_product(lv, b + 2u);
            let x3 = block_product(lv, b + 3u);
            sum = sum - x0;
            sum = sum - x1;
            sum = sum - x2;
            sum = sum - x3;
        }
    }
    for (; b < end; b = b + 1u) {
        sum = sum - block_product(lv, b);
    }
    return sum;
}

// Row r's correction after one block Gauss–Seidel update:
// A_rr⁻¹(rhs_r − Σ_{c≠r} A_rc·e_c) (zero where A_rr is singular: a pinned particle).
fn smooth_row(lv: Level, r: u32) -> vec3<f32> {
    let start = row_start(lv, r);
    let end = row_start(lv, r + 1u);
    let sum = subtract_row_products(rhs[lv.vec_base + r].xyz, lv, start + 1u, end);
    return solve3(block_at(lv.block_base + start), sum);
}

// Row r's residual rhs_r − Σ_c A_rc·e_c.
fn residual_row(lv: Level, r: u32) -> vec3<f32> {
    let start = row_start(lv, r);
    let end = row_start(lv, r + 1u);
    return subtract_row_products(rhs[lv.vec_base + r].xyz, lv, start, end);
}

// Coarse particle c's restricted residual: its finer children's residuals times their
// weights, in order (`coarse` is the level written, `finer` the level below it).
fn restrict_row(coarse: Level, finer: Level, c: u32) -> vec4<f32> {
    let start = hier[coarse.children_at + c];
    let end = hier[coarse.children_at + c + 1u];
    var sum = vec4<f32>(0.0);
    for (var t = start; t < end; t = t + 1u) {
        let f = hier[coarse.child_items_at + 2u * t];
        let w = bitcast<f32>(hier[coarse.child_items_at + 2u * t + 1u]);
        sum = sum + w * res[finer.vec_base + f];
    }
    return sum;
}

// The weighted sum of finer row i's three parents' corrections on the coarse level.
fn prolong_row(coarse: Level, i: u32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < 3u; k = k + 1u) {
        let parent = hier[coarse.parents_at + 3u * i + k];
        let w = bitcast<f32>(hier[coarse.weights_at + 3u * i + k]);
        sum = sum + w * e[coarse.vec_base + parent].xyz;
    }
    return sum;
}
