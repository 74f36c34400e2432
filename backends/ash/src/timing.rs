//! Per-pass GPU times: a timestamp query pool per queue, two queries per
//! pass, reset at the start of each batch that writes them. Frames recorded
//! with `Stamps::Frame` (record.rs) write only the lane's first and last. Ticks are masked
//! to the family's `timestampValidBits` and scaled by `timestampPeriod`.

use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use crate::owned::Owned;
use ash::vk;
use strandgraph_graph::Queue;
use strandgraph_graph::resolve::PassId;

/// One pass's GPU time on the queue it ran on.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PassTiming {
    pub pass: PassId,
    pub name: String,
    /// The queue the plan gave it.
    pub queue: Queue,
    /// The Vulkan queue family it ran on.
    pub family: u32,
    /// Workgroups (vertices for raster passes); `None` for an indirect
    /// dispatch whose arguments' bytes were aliased by the frame's end.
    pub workgroups: Option<u32>,
    /// `None` where the family has no timestamps (`timestampValidBits` 0).
    pub millis: Option<f64>,
    /// Begin and end in milliseconds from the frame's first timestamp on any
    /// queue (one device clock: overlap between queues shows here).
    pub span: Option<(f64, f64)>,
}

/// Query pools of the backend's queues.
pub(crate) struct Timestamps {
    /// Per backend queue: the pool (if the family has timestamps) and its size.
    pools: Vec<Option<(Owned<vk::QueryPool>, u32)>>,
    bits: Vec<u32>,
}

impl Timestamps {
    /// `passes[q]`: how many passes backend queue `q` runs.
    pub fn new(gpu: &Gpu, passes: &[usize]) -> Result<Self, AshError> {
        let mut pools = Vec::new();
        let mut bits = Vec::new();
        for (q, &n) in passes.iter().enumerate() {
            let valid = gpu.queues[q].timestamp_bits;
            bits.push(valid);
            if valid == 0 || n == 0 {
                pools.push(None);
                continue;
            }
            let count = (2 * n) as u32;
            let info = vk::QueryPoolCreateInfo::default()
                .query_type(vk::QueryType::TIMESTAMP)
                .query_count(count);
            let d = &gpu.device;
            // SAFETY: valid device and info.
            let pool = d.own(unsafe { d.create_query_pool(&info, None) }.ctx("vkCreateQueryPool")?);
            pools.push(Some((pool, count)));
        }
        Ok(Self { pools, bits })
    }

    /// Queue `q`'s pool, if its family has timestamps and it runs passes.
    pub fn pool(&self, q: usize) -> Option<vk::QueryPool> {
        self.pools[q].as_ref().map(|(pool, _)| pool.raw())
    }

    /// Raw ticks of every query of queue `q`'s pool, masked to the valid bits.
    pub fn read(&self, gpu: &Gpu, q: usize) -> Result<Option<Vec<u64>>, AshError> {
        let Some((pool, count)) = &self.pools[q] else {
            return Ok(None);
        };
        let mut ticks = vec![0u64; *count as usize];
        // SAFETY: the frame that wrote these queries has completed (the host
        // waited on every queue's timeline before reading).
        unsafe {
            gpu.device.get_query_pool_results(
                pool.raw(),
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .ctx("vkGetQueryPoolResults")?;
        let mask = self.mask(q);
        Ok(Some(ticks.into_iter().map(|t| t & mask).collect()))
    }

    /// Queries `a` and `b` of queue `q`'s pool, masked to the valid bits.
    pub fn read_pair(
        &self,
        gpu: &Gpu,
        q: usize,
        a: u32,
        b: u32,
    ) -> Result<Option<(u64, u64)>, AshError> {
        let Some((pool, _)) = &self.pools[q] else {
            return Ok(None);
        };
        let mask = self.mask(q);
        let mut ticks = [0u64; 2];
        for (t, query) in ticks.iter_mut().zip([a, b]) {
            *t = read_query(gpu, pool.raw(), query)? & mask;
        }
        Ok(Some((ticks[0], ticks[1])))
    }

    /// Queries `queries` of queue `q`'s pool, masked to the valid bits: only
    /// written ones (a reset query never written would be waited for).
    pub fn read_some(
        &self,
        gpu: &Gpu,
        q: usize,
        queries: impl Iterator<Item = u32>,
    ) -> Result<Option<Vec<u64>>, AshError> {
        let Some((pool, _)) = &self.pools[q] else {
            return Ok(None);
        };
        let mask = self.mask(q);
        let ticks: Result<Vec<u64>, AshError> = queries
            .map(|query| read_query(gpu, pool.raw(), query).map(|t| t & mask))
            .collect();
        ticks.map(Some)
    }

    pub fn mask(&self, q: usize) -> u64 {
        if self.bits[q] >= 64 {
            u64::MAX
        } else {
            (1u64 << self.bits[q]) - 1
        }
    }
}

/// One query's ticks, waiting for it.
fn read_query(gpu: &Gpu, pool: vk::QueryPool, query: u32) -> Result<u64, AshError> {
    let mut one = [0u64; 1];
    // SAFETY: the frame that wrote the query has completed (the host waited
    // on every queue's timeline before reading), and callers read only
    // queries that frame wrote.
    unsafe {
        gpu.device.get_query_pool_results(
            pool,
            query,
            &mut one,
            vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
        )
    }
    .ctx("vkGetQueryPoolResults")?;
    Ok(one[0])
}
