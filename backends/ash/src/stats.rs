//! What the driver compiled each compute pass into, from
//! `VK_KHR_pipeline_executable_properties`: with `STRANDGRAPH_PIPELINE_STATS`
//! set (to anything but `0`) and the extension present, every compute
//! pipeline is created with statistics capture and the driver's statistics
//! (on NVIDIA: registers per thread, shared memory, binary size) are logged
//! at `info` level under the pass's name. How many workgroups an SM holds
//! at once, and so how much memory latency a pass can hide, follows from
//! them; no timestamp shows it.
//!
//! ```sh
//! STRANDGRAPH_PIPELINE_STATS=1 RUST_LOG=strandgraph_ash=info strandgraph render scene.ron --backend ash
//! ```

use crate::owned::{Device, Instance};
use ash::{khr, vk};
use std::ffi::CStr;

/// The extension's functions, when statistics were asked for and the
/// device has them.
pub(crate) struct Stats {
    ext: khr::pipeline_executable_properties::Device,
}

/// Whether `STRANDGRAPH_PIPELINE_STATS` asks for statistics.
pub(crate) fn wanted() -> bool {
    std::env::var("STRANDGRAPH_PIPELINE_STATS").is_ok_and(|v| !v.is_empty() && v != "0")
}

/// Whether `physical` offers the extension.
pub(crate) fn supported(instance: &Instance, physical: vk::PhysicalDevice) -> bool {
    // SAFETY: plain query.
    let Ok(exts) = (unsafe { instance.enumerate_device_extension_properties(physical) }) else {
        return false;
    };
    exts.iter().any(|e| {
        e.extension_name_as_c_str() == Ok(khr::pipeline_executable_properties::NAME as &CStr)
    })
}

impl Stats {
    pub fn new(instance: &Instance, device: &Device) -> Self {
        Self {
            ext: khr::pipeline_executable_properties::Device::new(instance, device),
        }
    }

    /// Logs every statistic of every executable of `pipeline` (one compute
    /// stage: one executable) under `pass`. A query the driver refuses is
    /// logged, not an error: statistics are diagnostics.
    pub fn log(&self, pass: &str, pipeline: vk::Pipeline) {
        let info = vk::PipelineInfoKHR::default().pipeline(pipeline);
        // SAFETY: `pipeline` was created with CAPTURE_STATISTICS by this device.
        let executables = match unsafe { self.ext.get_pipeline_executable_properties(&info) } {
            Ok(e) => e,
            Err(e) => {
                tracing::warn!(pass, "vkGetPipelineExecutablePropertiesKHR: {e}");
                return;
            }
        };
        for index in 0..executables.len() as u32 {
            let exe = vk::PipelineExecutableInfoKHR::default()
                .pipeline(pipeline)
                .executable_index(index);
            // SAFETY: as above; `index` is below the executable count.
            match unsafe { self.ext.get_pipeline_executable_statistics(&exe) } {
                Ok(stats) => {
                    let line: Vec<String> = stats.iter().map(describe).collect();
                    tracing::info!(pass, "pipeline statistics: {}", line.join(", "));
                }
                Err(e) => tracing::warn!(pass, "vkGetPipelineExecutableStatisticsKHR: {e}"),
            }
        }
    }
}

/// `name = value` of one statistic.
fn describe(s: &vk::PipelineExecutableStatisticKHR<'_>) -> String {
    let name = s
        .name_as_c_str()
        .map_or("?".into(), |n| n.to_string_lossy());
    // SAFETY: the union member read is the one `format` names.
    let value = unsafe {
        match s.format {
            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => (s.value.b32 != 0).to_string(),
            vk::PipelineExecutableStatisticFormatKHR::INT64 => s.value.i64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::UINT64 => s.value.u64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => format!("{:.3}", s.value.f64),
            _ => "?".into(),
        }
    };
    format!("{name} = {value}")
}
