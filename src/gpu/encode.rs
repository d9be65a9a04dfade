//! Frame encoding: every substep of a batch in one compute pass and one submission, the
//! per-substep uniforms uploaded once per batch.

use super::solver::GpuSolver;
use crate::error::Error;
use crate::model::layout::SubstepParams;
use crate::plan::Pass;

impl GpuSolver {
    /// Runs the given stages (each must be in the plan) once per entry of `steps`, in one
    /// submission. `advance` runs the whole plan; parity tests run single stages.
    pub fn run_passes(&mut self, passes: &[Pass], steps: &[SubstepParams]) -> Result<(), Error> {
        self.ctx.check()?;
        let capacity = self.substeps.as_ref().map_or(usize::MAX, |s| s.capacity);
        let batches = steps.chunks(capacity.min(steps.len().max(1)));
        let last_batch = batches.len().saturating_sub(1);
        for (b, batch) in batches.enumerate() {
            if let Some(sb) = &self.substeps {
                let mut bytes = vec![0u8; sb.stride as usize * batch.len()];
                for (k, step) in batch.iter().enumerate() {
                    let at = k * sb.stride as usize;
                    bytes[at..at + std::mem::size_of::<SubstepParams>()]
                        .copy_from_slice(bytemuck::bytes_of(step));
                }
                self.ctx.queue.write_buffer(&sb.buffer, 0, &bytes);
            }
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            {
                let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("substeps"),
                    timestamp_writes: None,
                });
                for k in 0..batch.len() {
                    let substep_offset = self
                        .substeps
                        .as_ref()
                        .map(|sb| (k as u64 * sb.stride) as u32);
                    for &pass in passes {
                        if pass == Pass::VbdSolve {
                            let solve = self
                                .implicit
                                .as_ref()
                                .ok_or_else(|| Error::Gpu("vbd_solve is not in the plan".into()))?;
                            let offset = substep_offset.expect("the solve has substep params");
                            // The final force residual is read at the call's end only.
                            let measured = b == last_batch && k + 1 == batch.len();
                            solve.encode(&mut cpass, self.current, offset, measured);
                            continue;
                        }
                        let stage =
                            self.stages.iter().find(|s| s.pass == pass).ok_or_else(|| {
                                Error::Gpu(format!("{} is not in the plan", pass.name()))
                            })?;
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
                    }
                }
            }
            self.ctx.queue.submit([encoder.finish()]);
        }
        Ok(())
    }
}
