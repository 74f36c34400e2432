//! The roofline passes: definitions and CPU kernels
//! (WGSL: `shaders/bench/`).

use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx};
use crate::params::{Invalid, NoParams, PassParams, in_range};
use strandgraph_graph::Quantities;
use strandgraph_graph::schema::Quantity;

/// Invocations per workgroup of every roofline pass.
const GROUP: u32 = 256;
/// Default atomics per invocation: at 1920x1080, 16.6M atomics per pass,
/// enough to run for a measurable time on a fast GPU.
const OPS: u32 = 8;

/// PCG hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT
/// 2020): cheap, well mixed, and the same in WGSL (`shaders/bench/*.wgsl`).
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Salts that decorrelate values from addresses (any odd constants do).
const VALUE_SALT: u32 = 0x9e37_79b9;
const HIGH_SALT: u32 = 0x85eb_ca6b;

/// The atomic roofline passes' parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RooflineParams {
    /// Atomics per invocation (1..=256).
    pub ops_per_invocation: u32,
}

impl Default for RooflineParams {
    fn default() -> Self {
        Self {
            ops_per_invocation: OPS,
        }
    }
}

impl PassParams for RooflineParams {
    fn validate(&self) -> Result<(), Invalid> {
        in_range("ops_per_invocation", self.ops_per_invocation, 1..=256)
    }
}

crate::gpu_block! {
    /// `RooflineParams`: ops per invocation, invocations (pixels).
    pub struct RooflineGpu {
        ops: u32,
        invocations: u32,
    }
}

fn roofline_gpu(p: &RooflineParams, q: &Quantities) -> RooflineGpu {
    RooflineGpu {
        ops: p.ops_per_invocation,
        invocations: count(q.count(Quantity::Pixels)),
    }
}

/// One invocation per screen pixel, as many as the visibility buffer has.
const PER_PIXEL: Dispatch = Dispatch::PerElement {
    quantity: Quantity::Pixels,
    per_group: GROUP,
};

/// Tallies `n` atomics for the instrumented mode.
fn count_atomics(ctx: &Ctx<'_>, n: u64) {
    if ctx.instrument {
        ctx.counters.add(&CounterValues {
            atomics: n,
            ..CounterValues::default()
        });
    }
}

/// The global ids of workgroup `group` that exist (`< pixels`).
fn invocations(group: u32, ctx: &Ctx<'_>) -> std::ops::Range<u32> {
    let pixels = count(ctx.quantities.count(Quantity::Pixels));
    let start = group.saturating_mul(GROUP).min(pixels);
    start..start.saturating_add(GROUP).min(pixels)
}

pub static ATOMIC_MIN32: PassKind<RooflineParams, RooflineGpu> = PassKind {
    kind: "bench.atomic_min32",
    summary: "random-address 32-bit atomicMin into a visibility-atlas-sized buffer (roofline)",
    source: "strandgraph bench; Kulikov 2025 'Rasterization' (the operation measured)",
    bindings: Some(&[Binding::atomic("atomics_u32")]),
    workgroup_size: GROUP,
    dispatch: PER_PIXEL,
    shader: Shader::compute("bench/atomic_min32.wgsl", "atomic_min32"),
    kernel: |p| {
        Box::new(Min32 {
            ops: p.ops_per_invocation,
        })
    },
    gpu: roofline_gpu,
    raster: None,
};

pub static ATOMIC_MIN64: PassKind<RooflineParams, RooflineGpu> = PassKind {
    kind: "bench.atomic_min64",
    summary: "random-address 64-bit atomicMin, result unused, into a screen-sized 64-bit buffer (roofline)",
    source: "strandgraph bench; Lipp §3.1 (the operation measured)",
    bindings: Some(&[Binding::atomic("atomics_u64")]),
    workgroup_size: GROUP,
    dispatch: PER_PIXEL,
    shader: Shader::compute("bench/atomic_min64.wgsl", "atomic_min64"),
    kernel: |p| {
        Box::new(Min64 {
            ops: p.ops_per_invocation,
        })
    },
    gpu: roofline_gpu,
    raster: None,
};

struct Min32 {
    ops: u32,
}

impl CpuKernel for Min32 {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let target = ctx.words("atomics_u32");
        let len = target.len() as u32;
        if len == 0 {
            return;
        }
        let ids = invocations(group, ctx);
        let n = u64::from(ids.end - ids.start) * u64::from(self.ops);
        for id in ids {
            for k in 0..self.ops {
                let h = pcg(id.wrapping_mul(self.ops).wrapping_add(k));
                target.fetch_min(h as usize % len as usize, pcg(h ^ VALUE_SALT));
            }
        }
        count_atomics(ctx, n);
    }
}

struct Min64 {
    ops: u32,
}

impl CpuKernel for Min64 {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let target = ctx.words("atomics_u64");
        let len = target.len_u64().min(u32::MAX as usize) as u32;
        if len == 0 {
            return;
        }
        let ids = invocations(group, ctx);
        let n = u64::from(ids.end - ids.start) * u64::from(self.ops);
        for id in ids {
            for k in 0..self.ops {
                let h = pcg(id.wrapping_mul(self.ops).wrapping_add(k));
                let value = (u64::from(pcg(h ^ HIGH_SALT)) << 32) | u64::from(pcg(h ^ VALUE_SALT));
                target.fetch_min_u64((h % len) as usize, value);
            }
        }
        count_atomics(ctx, n);
    }
}

/// Words per invocation of `bench.copy` (one `vec4<u32>`).
const COPY_WORDS: u32 = 4;

crate::gpu_block! {
    /// `CopyParams`: unused padding (the shader sizes itself by arrayLength).
    pub struct CopyGpu {
        unused0: u32,
        unused1: u32,
    }
}

pub static COPY: PassKind<NoParams, CopyGpu> = PassKind {
    kind: "bench.copy",
    summary: "buffer-to-buffer copy in a compute shader (bandwidth roofline)",
    source: "strandgraph bench",
    bindings: Some(&[Binding::read("copy_src"), Binding::write("copy_dst")]),
    workgroup_size: GROUP,
    dispatch: Dispatch::CoverWrites {
        words_per_group: GROUP * COPY_WORDS,
    },
    shader: Shader::compute("bench/copy.wgsl", "copy"),
    kernel: |_| Box::new(CopyKernel),
    gpu: |_, _| CopyGpu::default(),
    raster: None,
};

struct CopyKernel;

impl CpuKernel for CopyKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let (src, dst) = (ctx.words("copy_src"), ctx.words("copy_dst"));
        let per_group = (GROUP * COPY_WORDS) as usize;
        // Whole vec4s only, as the shader copies array<vec4<u32>>.
        let end = src.len().min(dst.len()) / 4 * 4;
        // Past 65,535 workgroups (Dispatch::CoverWrites) the groups stride.
        let stride = per_group * ctx.workgroups.max(1) as usize;
        for start in (group as usize * per_group..end).step_by(stride) {
            for i in start..(start + per_group).min(end) {
                dst.store(i, src.load(i));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::harness::Harness;

    fn quantities(width: u32, height: u32) -> Quantities {
        let mut q = Quantities::example();
        q.width = width;
        q.height = height;
        q
    }

    /// The kernels perform exactly the hashed sequence: the buffer ends at
    /// the per-address minimum of an independent sequential replay.
    #[test]
    fn atomic_min_kernels_replay_the_hashed_sequence() {
        let q = quantities(40, 30);
        let pixels = 40 * 30;
        let groups = (pixels as u32).div_ceil(GROUP);
        let mut h = Harness::new(q);
        h.buffer("atomics_u32", vec![u32::MAX; 333]);
        h.buffer("atomics_u64", vec![u32::MAX; 2 * 111]);
        let c32 = h.run(&Min32 { ops: 3 }, groups, GROUP);
        let c64 = h.run(&Min64 { ops: 3 }, groups, GROUP);
        assert_eq!(c32.atomics, 3 * pixels);
        assert_eq!(c64.atomics, 3 * pixels);
        let mut e32 = vec![u32::MAX; 333];
        let mut e64 = vec![u64::MAX; 111];
        for id in 0..pixels as u32 {
            for k in 0..3 {
                let x = pcg(id * 3 + k);
                let a = x as usize % 333;
                e32[a] = e32[a].min(pcg(x ^ VALUE_SALT));
                let v = (u64::from(pcg(x ^ HIGH_SALT)) << 32) | u64::from(pcg(x ^ VALUE_SALT));
                let b = (x % 111) as usize;
                e64[b] = e64[b].min(v);
            }
        }
        assert_eq!(h.read("atomics_u32"), e32);
        let got: Vec<u64> = h
            .read("atomics_u64")
            .chunks(2)
            .map(|p| u64::from(p[0]) | (u64::from(p[1]) << 32))
            .collect();
        assert_eq!(got, e64);
        assert_eq!(h.out_of_bounds(), 0);
    }

    #[test]
    fn copy_copies_whole_vec4s() {
        let mut h = Harness::new(quantities(8, 8));
        let src: Vec<u32> = (0..2050).collect();
        h.buffer("copy_src", src.clone());
        h.buffer("copy_dst", vec![0; 2050]);
        h.run(&CopyKernel, 3, GROUP);
        let dst = h.read("copy_dst");
        assert_eq!(dst[..2048], src[..2048]);
        assert_eq!(dst[2048..], [0, 0]);
    }

    #[test]
    fn ops_out_of_range_is_refused() {
        let v: ron::Value = ron::from_str(r#"{"ops_per_invocation": 0}"#).unwrap();
        let e = crate::PassDef::cpu_kernel(&ATOMIC_MIN32, &v)
            .err()
            .expect("0 ops refused");
        assert!(e.to_string().contains("ops_per_invocation"), "{e}");
    }
}
