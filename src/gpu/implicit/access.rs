//! The solve's arrays read and written from the host, and operations run alone: for the
//! per-stage parity tests, which give a kernel and its CPU twin identical inputs.

use super::layout::{from_gpu, to_gpu, GpuMat3, SolveControl, SolveScalars};
use crate::error::Error;
use crate::gpu::GpuSolver;
use crate::model::layout::SubstepParams;
use crate::plan::SolveOp;
use glam::{Mat3, Vec4};

/// One of the solve's per-particle (or per-row) arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolveArray {
    /// The iterate D (w = inverse mass).
    Displacement,
    /// The inertial target Y.
    Target,
    /// Each body's contact plane per particle, body after body.
    Planes,
    /// Each particle's normal force per body.
    Lambdas,
    /// The fine force at the last assembly.
    Force,
    /// The Newton correction c.
    Correction,
    /// Conjugate gradients' direction p.
    Direction,
    /// H·p.
    Product,
    /// A level's right-hand side (level 0: r).
    Rhs(u32),
    /// A level's correction (level 0: z).
    LevelCorrection(u32),
    /// A level's residual.
    LevelResidual(u32),
    /// The reductions' per-workgroup partials.
    Partials,
}

impl GpuSolver {
    fn solve(&self) -> Result<&super::ImplicitSolve, Error> {
        self.implicit
            .as_ref()
            .ok_or_else(|| Error::Gpu("implicit Euler is not in the plan".into()))
    }

    /// The buffer and the range of 16-byte entries of `array`.
    fn solve_range(&self, array: SolveArray) -> Result<(&wgpu::Buffer, usize, usize), Error> {
        let s = self.solve()?;
        let b = &s.buffers;
        let n = s.n as usize;
        let level = |l: u32| -> Result<(usize, usize), Error> {
            let lv =
                (s.levels.get(l as usize)).ok_or_else(|| Error::Gpu(format!("no level {l}")))?;
            Ok((lv.vec_base as usize, lv.rows as usize))
        };
        let whole = |buffer: &wgpu::Buffer| (buffer.size() / 16) as usize;
        Ok(match array {
            SolveArray::Displacement => (&b.disp, 0, n),
            SolveArray::Target => (&b.target, 0, n),
            SolveArray::Planes => (&b.planes, 0, whole(&b.planes)),
            SolveArray::Lambdas => (&b.lambdas, 0, n),
            SolveArray::Force => (&b.force, 0, n),
            SolveArray::Correction => (&b.correction, 0, n),
            SolveArray::Direction => (&b.p, 0, n),
            SolveArray::Product => (&b.ap, 0, n),
            SolveArray::Rhs(l) => (&b.rhs, level(l)?.0, level(l)?.1),
            SolveArray::LevelCorrection(l) => (&b.e, level(l)?.0, level(l)?.1),
            SolveArray::LevelResidual(l) => (&b.res, level(l)?.0, level(l)?.1),
            SolveArray::Partials => (&b.partials, 0, whole(&b.partials)),
        })
    }

    /// Reads one of the solve's arrays back.
    pub fn solve_array(&self, array: SolveArray) -> Result<Vec<Vec4>, Error> {
        let (buffer, start, len) = self.solve_range(array)?;
        let words = self.read_u32(buffer)?;
        let all: &[Vec4] = bytemuck::cast_slice(&words);
        Ok(all[start..start + len].to_vec())
    }

    /// Overwrites one of the solve's arrays (from its start, `data.len()` entries).
    pub fn set_solve_array(&mut self, array: SolveArray, data: &[Vec4]) -> Result<(), Error> {
        let (buffer, start, len) = self.solve_range(array)?;
        if data.len() > len {
            return Err(Error::Gpu(format!("{array:?} holds {len} entries")));
        }
        let bytes = bytemuck::cast_slice(data);
        self.ctx
            .queue
            .write_buffer(buffer, 16 * start as u64, bytes);
        Ok(())
    }

    /// The blocks of a level's matrix (level 0: the fine Hessian), in its pattern's order.
    pub fn solve_blocks(&self, level: u32) -> Result<Vec<Mat3>, Error> {
        let s = self.solve()?;
        let lv =
            (s.levels.get(level as usize)).ok_or_else(|| Error::Gpu("no such level".into()))?;
        let words = self.read_u32(&s.buffers.blocks)?;
        let all: &[GpuMat3] = bytemuck::cast_slice(&words);
        let range = lv.block_base as usize..(lv.block_base + lv.blocks) as usize;
        Ok(all[range].iter().map(from_gpu).collect())
    }

    /// Overwrites the blocks of a level's matrix (and their texels).
    pub fn set_solve_blocks(&mut self, level: u32, blocks: &[Mat3]) -> Result<(), Error> {
        let s = self.solve()?;
        let lv =
            (s.levels.get(level as usize)).ok_or_else(|| Error::Gpu("no such level".into()))?;
        let data: Vec<GpuMat3> = blocks.iter().map(|m| to_gpu(*m)).collect();
        let at = 48 * lv.block_base as u64;
        (self.ctx.queue).write_buffer(&s.buffers.blocks, at, bytemuck::cast_slice(&data));
        let ctx = self.ctx.clone();
        let solve = self.implicit.as_mut().expect("checked above");
        solve.publish(&ctx, level)
    }

    /// The conjugate-gradient and line-search scalars.
    pub fn solve_scalars(&self) -> Result<SolveScalars, Error> {
        let words = self.read_u32(&self.solve()?.buffers.scalars)?;
        let len = std::mem::size_of::<SolveScalars>() / 4;
        Ok(*bytemuck::from_bytes(bytemuck::cast_slice(&words[..len])))
    }

    /// Overwrites the conjugate-gradient and line-search scalars.
    pub fn set_solve_scalars(&mut self, scalars: SolveScalars) -> Result<(), Error> {
        let buffer = &self.solve()?.buffers.scalars;
        self.ctx
            .queue
            .write_buffer(buffer, 0, bytemuck::bytes_of(&scalars));
        Ok(())
    }

    /// The solve's control words (the last force residual, and whether a tolerance check ended
    /// the last substep's solve).
    pub fn solve_control(&self) -> Result<SolveControl, Error> {
        let words = self.read_u32(&self.solve()?.buffers.control)?;
        Ok(*bytemuck::from_bytes(bytemuck::cast_slice(&words[..4])))
    }

    /// The substep's operations, as the solve runs them.
    pub fn solve_schedule(&self) -> Result<Vec<SolveOp>, Error> {
        Ok(self.solve()?.schedule().to_vec())
    }

    /// Runs `ops` of the solve alone, in one submission, as within a substep with `step`'s
    /// values (xₙ: the current positions). Each must be an operation of this solver's
    /// schedule.
    pub fn run_solve_ops(&mut self, ops: &[SolveOp], step: &SubstepParams) -> Result<(), Error> {
        self.ctx.check()?;
        let ctx = self.ctx.clone();
        let parity = self.current;
        let substeps = self
            .substeps
            .as_ref()
            .expect("the solve has substep params");
        ctx.queue
            .write_buffer(&substeps.buffer, 0, bytemuck::bytes_of(step));
        let solve = self
            .implicit
            .as_mut()
            .ok_or_else(|| Error::Gpu("implicit Euler is not in the plan".into()))?;
        let dispatches = solve.dispatches_for(&ctx, ops)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut cpass = encoder.begin_compute_pass(&Default::default());
            solve.encode_dispatches(&mut cpass, &dispatches, parity, 0, None);
        }
        ctx.queue.submit([encoder.finish()]);
        Ok(())
    }
}
