// Every level's matrix blocks as the kernels that sweep, multiply and coarsen read them: three
// rgba32float texels per block (its columns), published from the blocks buffer after each
// assembly and Galerkin product (publish_blocks.wgsl). A texel fetch loads a column at once,
// where a storage-buffer gather on a software adapter loads it lane by lane and component by
// component (see common.wgsl). Composed into smooth, level_residual, coarse_cycle, pcg_matvec
// and coarse_operator.

@group(0) @binding(31) var block_texels: texture_2d<f32>;
// The column of every block of all levels (hierarchy.wgsl's column(), as texels: r32uint).
@group(0) @binding(32) var block_columns: texture_2d<u32>;

// Block b of all levels (a level's block k is at its block_base + k).
fn block_at(b: u32) -> mat3x3<f32> {
    let t = 3u * b;
    return mat3x3<f32>(
        textureLoad(block_texels, texel(t), 0).xyz,
        textureLoad(block_texels, texel(t + 1u), 0).xyz,
        textureLoad(block_texels, texel(t + 2u), 0).xyz,
    );
}

// The column of block b of level lv (b: the level's own block index).
fn block_column(lv: Level, b: u32) -> u32 {
    return textureLoad(block_columns, texel(lv.block_base + b), 0).x;
}
