//! wgpu behind the backends' one interface
//! ([`strandgraph_passes::backend::Session`]).

use crate::Session;
use strandgraph_passes::backend::{self as api, BackendError, Clock, PassTime};
use strandgraph_passes::upload::Upload;

impl api::Session for Session {
    fn backend(&self) -> &'static str {
        "wgpu"
    }

    fn device(&self) -> String {
        self.gpu.name.clone()
    }

    fn clock(&self) -> Clock {
        Clock::GpuTimestamps
    }

    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }

    fn run(&mut self, inputs: &Upload) -> Result<Vec<PassTime>, BackendError> {
        Session::run(self, inputs).map_err(|e| BackendError::new("wgpu", e))?;
        let plan = &self.plan;
        Ok(self
            .timings
            .iter()
            .map(|t| PassTime {
                pass: t.pass,
                name: t.name.clone(),
                kind: plan.graph.passes[t.pass].kind.clone(),
                queue: t.queue,
                workgroups: Some(u64::from(t.workgroups)),
                millis: Some(t.millis),
                span: None,
                family: None,
                counters: None,
            })
            .collect())
    }

    fn read(&self, name: &str) -> Result<Option<Vec<u32>>, BackendError> {
        Session::read(self, &self.plan, name).map_err(|e| BackendError::new("wgpu", e))
    }
}
