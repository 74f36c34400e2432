//! ash behind the backends' one interface
//! ([`strandgraph_passes::backend::Session`]).

use crate::Session;
use strandgraph_passes::backend::{self as api, BackendError, Clock, PassTime};
use strandgraph_passes::upload::Upload;

impl api::Session for Session {
    fn backend(&self) -> &'static str {
        "ash"
    }

    fn device(&self) -> String {
        self.device.clone()
    }

    fn clock(&self) -> Clock {
        Clock::GpuTimestamps
    }

    fn notes(&self) -> Vec<String> {
        let mib = |b: u64| b as f64 / (1 << 20) as f64;
        let mut notes = self.notes.clone();
        notes.push(format!(
            "transients {:.2} MiB aliased, {:.2} MiB unaliased",
            mib(self.transient_bytes),
            mib(self.unaliased_bytes)
        ));
        notes
    }

    fn run(&mut self, inputs: &Upload) -> Result<Vec<PassTime>, BackendError> {
        let frame = Session::run(self, inputs).map_err(|e| BackendError::new("ash", e))?;
        let plan = self.plan();
        Ok(frame
            .timings
            .iter()
            .map(|t| PassTime {
                pass: t.pass,
                name: t.name.clone(),
                kind: plan.graph.passes[t.pass].kind.clone(),
                queue: t.queue,
                workgroups: t.workgroups.map(u64::from),
                millis: t.millis,
                span: t.span,
                family: Some(t.family),
                counters: None,
            })
            .collect())
    }

    fn run_frame_timed(&mut self, inputs: &Upload) -> Result<Option<f64>, BackendError> {
        Session::run_frame_timed(self, inputs).map_err(|e| BackendError::new("ash", e))
    }

    fn run_levels_timed(
        &mut self,
        inputs: &Upload,
    ) -> Result<Option<Vec<api::LevelTime>>, BackendError> {
        Session::run_levels_timed(self, inputs)
            .map(Some)
            .map_err(|e| BackendError::new("ash", e))
    }

    fn read(&self, name: &str) -> Result<Option<Vec<u32>>, BackendError> {
        Session::read(self, name).map_err(|e| BackendError::new("ash", e))
    }
}
