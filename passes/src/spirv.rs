//! SPIR-V post-processing shared by the GPU backends.
//!
//! [`forbid_contraction`] decorates every floating-point arithmetic result
//! `NoContraction`. Without it a Vulkan driver may fuse `a * b + c` into one
//! FMA (NVIDIA does, widely), which rounds once instead of twice: the GPU
//! then computes different bits from the same WGSL than the CPU simulator,
//! which rounds every operation as written. The per-pass agreement harness
//! (`strandgraph agree`) measured this on an H100: `kulikov.skin` alone,
//! from identical inputs, disagreed on 11.6% of its clip-space words.
//! WGSL has no way to say this; naga's SPIR-V writer has no option for it.

/// Whether the GPU backends let the driver contract float arithmetic:
/// `STRANDGRAPH_FLOAT_CONTRACTION=1` (a switch for measuring what exact
/// rounding costs; off by default, so backends agree with the simulator).
pub fn contraction_allowed() -> bool {
    std::env::var_os("STRANDGRAPH_FLOAT_CONTRACTION").is_some_and(|v| v == "1")
}

/// `OpDecorate`, and the `NoContraction` decoration (SPIR-V 1.6 §3.20).
const OP_DECORATE: u32 = 71;
const NO_CONTRACTION: u32 = 42;

/// Float arithmetic opcodes a driver may contract (SPIR-V §3.49.13, the
/// floating-point ones): FNegate, FAdd, FSub, FMul, FDiv, FRem, FMod,
/// VectorTimesScalar, MatrixTimesScalar, VectorTimesMatrix,
/// MatrixTimesVector, MatrixTimesMatrix, OuterProduct, Dot.
const FLOAT_ARITHMETIC: [u32; 14] = [
    127, 129, 131, 133, 136, 140, 141, 142, 143, 144, 145, 146, 147, 148,
];

/// Types start the section after the annotations (SPIR-V §2.4 logical
/// layout): OpTypeVoid ..= OpTypeForwardPointer.
fn is_type(opcode: u32) -> bool {
    (19..=39).contains(&opcode)
}

/// A malformed module (the words did not come from a SPIR-V writer).
#[derive(Debug, Clone, thiserror::Error)]
#[error("SPIR-V: {0}")]
pub struct SpirvError(String);

/// Adds `OpDecorate %r NoContraction` for the result `%r` of every float
/// arithmetic instruction of `words`, a whole SPIR-V module. Returns how many
/// results it decorated.
pub fn forbid_contraction(words: &mut Vec<u32>) -> Result<usize, SpirvError> {
    const HEADER: usize = 5;
    if words.len() < HEADER || words[0] != 0x0723_0203 {
        return Err(SpirvError("no SPIR-V magic number".into()));
    }
    let mut results = Vec::new();
    let mut first_type = None;
    let mut at = HEADER;
    while at < words.len() {
        let (count, opcode) = ((words[at] >> 16) as usize, words[at] & 0xffff);
        if count == 0 || at + count > words.len() {
            return Err(SpirvError(format!(
                "instruction at word {at} has length {count}"
            )));
        }
        if is_type(opcode) && first_type.is_none() {
            first_type = Some(at);
        }
        // Result type at word 1, result id at word 2.
        if FLOAT_ARITHMETIC.contains(&opcode) && count >= 3 {
            results.push(words[at + 2]);
        }
        at += count;
    }
    let insert = first_type.ok_or_else(|| SpirvError("module declares no type".into()))?;
    let decorations = results
        .iter()
        .flat_map(|&id| [(3 << 16) | OP_DECORATE, id, NO_CONTRACTION]);
    words.splice(insert..insert, decorations);
    Ok(results.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal module: header, OpCapability Shader, OpTypeFloat 32,
    /// two float ops (FMul, FAdd) and an integer op (IAdd, 128).
    fn module() -> Vec<u32> {
        vec![
            0x0723_0203,
            0x0001_0300,
            0,
            20,
            0,
            (2 << 16) | 17, // OpCapability
            1,
            (3 << 16) | 22, // OpTypeFloat %1 32
            1,
            32,
            (5 << 16) | 133, // OpFMul %1 %10 %2 %3
            1,
            10,
            2,
            3,
            (5 << 16) | 129, // OpFAdd %1 %11 %10 %4
            1,
            11,
            10,
            4,
            (5 << 16) | 128, // OpIAdd %1 %12 ...
            1,
            12,
            5,
            6,
        ]
    }

    #[test]
    fn float_results_are_decorated_before_the_types() {
        let mut words = module();
        let n = forbid_contraction(&mut words).unwrap();
        assert_eq!(n, 2);
        // The decorations sit where the type declaration was.
        assert_eq!(
            &words[7..13],
            &[(3 << 16) | 71, 10, 42, (3 << 16) | 71, 11, 42]
        );
        assert_eq!(words[13], (3 << 16) | 22);
        assert_eq!(words.len(), module().len() + 6);
    }

    #[test]
    fn malformed_modules_are_errors() {
        assert!(forbid_contraction(&mut vec![1, 2, 3]).is_err());
        let mut truncated = module();
        truncated.truncate(12);
        assert!(forbid_contraction(&mut truncated).is_err());
    }
}
