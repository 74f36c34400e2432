//! Comparing one output of one pass between the CPU simulator and a GPU
//! backend, element by element, under the output's [`Rule`].

use serde::Serialize;
use strandgraph_graph::schema::{ImageFormat, ResourceDecl};
use strandgraph_passes::lipp::shaded::unpack_rgb9e5;

/// How closely a GPU output must match the CPU's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Rule {
    /// Every 32-bit word identical.
    Exact,
    /// 32-bit floats within `ulps` units in the last place, or within
    /// `abs` of each other (for values near zero, where ULPs are tiny).
    F32 { ulps: u32, abs: f32 },
    /// Pairs of 16-bit floats (half images), within `ulps` of each other.
    F16 { ulps: u32 },
    /// Bytes of 8-bit UNORM texels, within `steps` of each other.
    Unorm8 { steps: u32 },
    /// Pairs of 16-bit UNORM codes, within `steps` of each other.
    Unorm16 { steps: u32 },
    /// The same words in any order: the order is set by which GPU thread
    /// wins an atomic slot, and every consumer is order-independent.
    Multiset,
    /// Unsigned counts (fixed-point sums) within `max` of each other.
    Near { max: u32 },
    /// `lipp.shade`'s records (passes/src/lipp/shaded.rs): even words RGB9E5
    /// colours whose channels are within `rel` of the brighter colour's
    /// largest channel (or `abs`), odd words (depth and flags) identical.
    Rgb9e5Records { rel: f32, abs: f32 },
}

/// The rule for an image format: exact unless it stores floats or UNORMs.
pub fn format_rule(format: ImageFormat) -> Rule {
    use ImageFormat::*;
    match format {
        R32Uint | Rg32Uint => Rule::Exact,
        R32Float | Rgba32Float | D32Float => Rule::F32 { ulps: 4, abs: 1e-6 },
        R16Float | Rg16Float | Rgba16Float => Rule::F16 { ulps: 1 },
        R8Unorm | Rgba8Unorm | Rgba8Srgb => Rule::Unorm8 { steps: 1 },
    }
}

/// The default rule for a declared resource.
pub fn default_rule(decl: &ResourceDecl) -> Rule {
    match decl {
        ResourceDecl::Image { format, .. } => format_rule(*format),
        ResourceDecl::Buffer { .. } => Rule::Exact,
    }
}

/// How one output compared.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    pub words: usize,
    /// Words that are not bit-identical.
    pub differing: usize,
    /// Elements outside the rule's bound.
    pub failing: usize,
    /// The largest difference in the rule's unit (ULPs, steps; 0 or 1 for
    /// exact and multiset comparisons).
    pub worst: f64,
    /// The first failing word, for the report.
    pub first_failure: Option<usize>,
    /// Whatever the rule: the largest difference of differing words read
    /// as unsigned integers, and read as f32 in ULPs (what a rule would
    /// have to allow).
    pub max_int: u64,
    pub max_f32_ulps: u64,
    /// Failing elements the output's judgement allows (its outliers).
    pub allowed: usize,
}

impl Outcome {
    pub fn passed(&self) -> bool {
        self.failing <= self.allowed
    }
}

/// Compares `gpu` against `cpu` under `rule`. Lengths may differ by the
/// backends' padding; words past the shorter are compared with zero.
pub fn compare(cpu: &[u32], gpu: &[u32], rule: Rule) -> Outcome {
    let n = cpu.len().max(gpu.len());
    let at = |v: &[u32], i: usize| v.get(i).copied().unwrap_or(0);
    let differing = (0..n).filter(|&i| at(cpu, i) != at(gpu, i)).count();
    let mut out = Outcome {
        words: n,
        differing,
        failing: 0,
        worst: 0.0,
        first_failure: None,
        max_int: 0,
        max_f32_ulps: 0,
        allowed: 0,
    };
    for i in 0..n {
        let (c, g) = (at(cpu, i), at(gpu, i));
        if c != g {
            out.max_int = out.max_int.max(u64::from(c.abs_diff(g)));
            out.max_f32_ulps = out.max_f32_ulps.max(ulp_distance(c, g));
        }
    }
    if rule == Rule::Multiset {
        let (mut a, mut b) = (cpu.to_vec(), gpu.to_vec());
        a.resize(n, 0);
        b.resize(n, 0);
        a.sort_unstable();
        b.sort_unstable();
        let failing = a.iter().zip(&b).filter(|(x, y)| x != y).count();
        out.failing = failing;
        out.worst = f64::from(u8::from(failing > 0));
        out.first_failure = (failing > 0).then_some(0);
        return out;
    }
    for i in 0..n {
        let (c, g) = (at(cpu, i), at(gpu, i));
        if c == g {
            continue;
        }
        let error = match rule {
            Rule::Rgb9e5Records { .. } if i % 2 == 1 => word_error(c, g, Rule::Exact),
            _ => word_error(c, g, rule),
        };
        out.worst = out.worst.max(error.0);
        if !error.1 {
            out.failing += 1;
            out.first_failure.get_or_insert(i);
        }
    }
    out
}

/// The difference of two words in the rule's unit, and whether it is within bounds.
fn word_error(c: u32, g: u32, rule: Rule) -> (f64, bool) {
    match rule {
        Rule::Exact | Rule::Multiset => (1.0, false),
        Rule::F32 { ulps, abs } => {
            let (x, y) = (f32::from_bits(c), f32::from_bits(g));
            let d = ulp_distance(c, g);
            let ok = d <= u64::from(ulps) || (x - y).abs() <= abs;
            (d as f64, ok)
        }
        Rule::F16 { ulps } => {
            let d = [c & 0xffff, c >> 16]
                .iter()
                .zip([g & 0xffff, g >> 16])
                .map(|(&a, b)| half_ulp_distance(a as u16, b as u16))
                .max()
                .unwrap_or(0);
            (d as f64, d <= u64::from(ulps))
        }
        Rule::Near { max } => {
            let d = c.abs_diff(g);
            (f64::from(d), d <= max)
        }
        Rule::Rgb9e5Records { rel, abs } => {
            let (x, y) = (unpack_rgb9e5(c), unpack_rgb9e5(g));
            let bright = x.into_iter().chain(y).fold(0.0f32, f32::max);
            let d = (0..3).map(|k| (x[k] - y[k]).abs()).fold(0.0f32, f32::max);
            // In units of the brighter colour's largest channel.
            let error = if bright > 0.0 { d / bright } else { 0.0 };
            (f64::from(error), d <= rel * bright || d <= abs)
        }
        Rule::Unorm16 { steps } => {
            let d = [0, 16]
                .map(|k| ((c >> k) & 0xffff).abs_diff((g >> k) & 0xffff))
                .into_iter()
                .max()
                .unwrap_or(0);
            (f64::from(d), d <= steps)
        }
        Rule::Unorm8 { steps } => {
            let d = (0..4)
                .map(|k| ((c >> (8 * k)) & 0xff).abs_diff((g >> (8 * k)) & 0xff))
                .max()
                .unwrap_or(0);
            (f64::from(d), d <= steps)
        }
    }
}

/// Distance of two floats in units in the last place, across zero (a NaN is
/// infinitely far from everything but its own bits).
pub fn ulp_distance(a: u32, b: u32) -> u64 {
    let key = |bits: u32| -> Option<i64> {
        let f = f32::from_bits(bits);
        if f.is_nan() {
            return None;
        }
        // Monotonic integer order of floats: negative floats count down from -0.
        let mag = i64::from(bits & 0x7fff_ffff);
        Some(if bits >> 31 == 1 { -mag } else { mag })
    };
    match (key(a), key(b)) {
        (Some(x), Some(y)) => x.abs_diff(y),
        _ => u64::MAX,
    }
}

fn half_ulp_distance(a: u16, b: u16) -> u64 {
    let key = |bits: u16| -> Option<i64> {
        if bits & 0x7c00 == 0x7c00 && bits & 0x03ff != 0 {
            return None;
        }
        let mag = i64::from(bits & 0x7fff);
        Some(if bits >> 15 == 1 { -mag } else { mag })
    };
    match (key(a), key(b)) {
        (Some(x), Some(y)) => x.abs_diff(y),
        _ => u64::MAX,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ulps_count_across_zero_and_refuse_nan() {
        assert_eq!(ulp_distance(1.0f32.to_bits(), 1.0f32.to_bits()), 0);
        let next = f32::from_bits(1.0f32.to_bits() + 3);
        assert_eq!(ulp_distance(1.0f32.to_bits(), next.to_bits()), 3);
        assert_eq!(ulp_distance(0.0f32.to_bits(), (-0.0f32).to_bits()), 0);
        let tiny = f32::from_bits(1);
        assert_eq!(ulp_distance(tiny.to_bits(), (-tiny).to_bits()), 2);
        assert_eq!(
            ulp_distance(f32::NAN.to_bits(), f32::NAN.to_bits()),
            u64::MAX
        );
    }

    #[test]
    fn rules_bound_what_they_say() {
        let one = 1.0f32.to_bits();
        let f = Rule::F32 { ulps: 4, abs: 0.0 };
        assert!(compare(&[one], &[one + 4], f).passed());
        assert!(!compare(&[one], &[one + 5], f).passed());
        assert!(!compare(&[one], &[one + 1], Rule::Exact).passed());
        assert!(compare(&[1, 2, 3], &[3, 1, 2], Rule::Multiset).passed());
        assert!(!compare(&[1, 2, 3], &[3, 1, 1], Rule::Multiset).passed());
        let u = Rule::Unorm8 { steps: 1 };
        assert!(compare(&[0x0101_0101], &[0x0201_0100], u).passed());
        assert!(!compare(&[0x0101_0101], &[0x0301_0101], u).passed());
        let w = Rule::Unorm16 { steps: 1 };
        assert!(compare(&[0x0005_fffe], &[0x0004_ffff], w).passed());
        assert!(!compare(&[0x0005_0000], &[0x0007_0000], w).passed());
        let h = Rule::F16 { ulps: 1 };
        assert!(compare(&[0x3c00_3c00], &[0x3c01_3c00], h).passed());
        assert!(!compare(&[0x3c00_3c00], &[0x3c00_3c02], h).passed());
        // Padding: a longer GPU buffer compares its tail with zero.
        assert!(compare(&[7], &[7, 0, 0], Rule::Exact).passed());
        use strandgraph_passes::lipp::shaded::pack_rgb9e5;
        let r = Rule::Rgb9e5Records {
            rel: 0.01,
            abs: 0.0,
        };
        let (a, b) = (pack_rgb9e5([1.0, 0.5, 0.0]), pack_rgb9e5([1.005, 0.5, 0.0]));
        assert!(compare(&[a, 9], &[b, 9], r).passed());
        assert!(!compare(&[a, 9], &[b, 8], r).passed(), "odd words exact");
        let c = pack_rgb9e5([1.0, 0.52, 0.0]);
        assert!(!compare(&[a, 9], &[c, 9], r).passed());
    }
}
