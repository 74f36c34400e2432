//! A frame timed level by level ([`Stamps::Levels`]): each batch's start
//! after its waits and the end of each of its dependency levels, so a
//! queue's passes overlap as they do untimed and the timeline still shows
//! which level, and which queue's chain of levels, the frame waits for.

use crate::error::AshError;
use crate::record::Stamps;
use crate::session::Session;
use strandgraph_passes::backend::LevelTime;
use strandgraph_passes::upload::Upload;

impl Session {
    /// Runs one frame as [`Session::run`] does, timed level by level;
    /// returns every batch's levels, lane by lane, in ms from the frame's
    /// first batch start. Queues without timestamps give none.
    pub fn run_levels_timed(&mut self, inputs: &Upload) -> Result<Vec<LevelTime>, AshError> {
        self.run_with(inputs, Stamps::Levels)?;
        let levels = self.level_spans()?;
        self.gpu.check("the frame")?;
        Ok(levels)
    }

    fn level_spans(&self) -> Result<Vec<LevelTime>, AshError> {
        let period = f64::from(self.gpu.props.limits.timestamp_period);
        let g = &self.plan.graph;
        // Per lane and batch: the batch's start, then each level's end.
        let mut stamps = Vec::new();
        for lane in &self.lanes.lanes {
            let mut batches = Vec::new();
            for batch in &lane.batches {
                let first = 2 * batch.first as u32;
                let queries = first..=first + batch.levels.len() as u32;
                let ticks = self.timestamps.read_some(&self.gpu, lane.queue, queries)?;
                batches.push(ticks);
            }
            stamps.push(batches);
        }
        let origin = stamps
            .iter()
            .flatten()
            .filter_map(|t| t.as_ref().and_then(|t| t.first().copied()))
            .min();
        let Some(origin) = origin else {
            return Ok(Vec::new());
        };
        let mut out = Vec::new();
        for (lane, batches) in self.lanes.lanes.iter().zip(&stamps) {
            let mask = self.timestamps.mask(lane.queue);
            // Ticks after the origin, across a counter wrap.
            let ms = |t: u64| (t.wrapping_sub(origin) & mask) as f64 * period / 1e6;
            for (b, (batch, ticks)) in lane.batches.iter().zip(batches).enumerate() {
                let Some(ticks) = ticks else { continue };
                for (k, level) in batch.levels.iter().enumerate() {
                    out.push(LevelTime {
                        queue: lane.queue,
                        batch: b,
                        passes: level
                            .iter()
                            .map(|&i| g.passes[lane.passes[i]].name.clone())
                            .collect(),
                        span: (ms(ticks[k]), ms(ticks[k + 1])),
                    });
                }
            }
        }
        Ok(out)
    }
}
