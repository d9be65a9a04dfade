//! Frame encoding: every substep of a batch in one compute pass and one submission, the
//! per-substep uniforms uploaded once per batch. A profiled solver submits one substep at a
//! time, with a timestamp after every stage.

use super::solver::GpuSolver;
use crate::error::Error;
use crate::model::layout::SubstepParams;
use crate::plan::Pass;

impl GpuSolver {
    /// Runs the given stages (each must be in the plan) once per entry of `steps`, in one
    /// submission. `advance` runs the whole plan; parity tests run single stages.
    pub fn run_passes(&mut self, passes: &[Pass], steps: &[SubstepParams]) -> Result<(), Error> {
        self.ctx.check()?;
        let mut capacity = self.substeps.as_ref().map_or(usize::MAX, |s| s.capacity);
        if self.profile.is_some() {
            // One query set is resolved and read back per submission: one substep each.
            capacity = 1;
        }
        let batches = steps.chunks(capacity.min(steps.len().max(1)));
        let last_batch = batches.len().saturating_sub(1);
        for (b, batch) in batches.enumerate() {
            self.upload_substeps(batch);
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            {
                let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("substeps"),
                    timestamp_writes: None,
                });
                if let Some(p) = self.profile.as_mut() {
                    p.begin(&mut cpass);
                }
                for k in 0..batch.len() {
                    // The final force residual is read at the call's end only.
                    let measured = b == last_batch && k + 1 == batch.len();
                    self.encode_substep(&mut cpass, passes, k, measured)?;
                }
            }
            if let Some(p) = &self.profile {
                p.resolve(&mut encoder);
            }
            self.ctx.queue.submit([encoder.finish()]);
            if let Some(p) = self.profile.as_mut() {
                p.collect(&self.ctx)?;
            }
        }
        Ok(())
    }

    /// Writes the batch's per-substep uniforms.
    fn upload_substeps(&self, batch: &[SubstepParams]) {
        let Some(sb) = &self.substeps else {
            return;
        };
        let mut bytes = vec![0u8; sb.stride as usize * batch.len()];
        for (k, step) in batch.iter().enumerate() {
            let at = k * sb.stride as usize;
            bytes[at..at + std::mem::size_of::<SubstepParams>()]
                .copy_from_slice(bytemuck::bytes_of(step));
        }
        self.ctx.queue.write_buffer(&sb.buffer, 0, &bytes);
    }

    /// Encodes the `k`-th substep of a batch: every stage of `passes` in order.
    fn encode_substep(
        &mut self,
        cpass: &mut wgpu::ComputePass,
        passes: &[Pass],
        k: usize,
        measured: bool,
    ) -> Result<(), Error> {
        let substep_offset = (self.substeps.as_ref()).map(|sb| (k as u64 * sb.stride) as u32);
        for &pass in passes {
            if pass == Pass::VbdSolve {
                let solve = (self.implicit.as_ref())
                    .ok_or_else(|| Error::Gpu("vbd_solve is not in the plan".into()))?;
                let offset = substep_offset.expect("the solve has substep params");
                solve.encode(cpass, self.current, offset, measured, self.profile.as_mut());
                continue;
            }
            let stage = (self.stages.iter().find(|s| s.pass == pass))
                .ok_or_else(|| Error::Gpu(format!("{} is not in the plan", pass.name())))?;
            cpass.set_pipeline(&stage.pipeline);
            let offset = match (substep_offset, stage.uses_substep) {
                (Some(o), true) => vec![o],
                _ => vec![],
            };
            if let Some(force_in) = &stage.force_in {
                cpass.set_bind_group(1, force_in, &[]);
            }
            if let Some(out) = stage.force_out {
                self.last_forces = out;
            }
            for _ in 0..stage.repeats {
                cpass.set_bind_group(0, &stage.bind_groups[self.current], &offset);
                cpass.dispatch_workgroups(stage.dispatch.0, stage.dispatch.1, 1);
                if pass.writes_state() {
                    self.current = 1 - self.current;
                }
            }
            if let Some(p) = self.profile.as_mut() {
                p.mark(cpass, stage.repeats, || pass.name().to_string());
            }
        }
        Ok(())
    }
}
