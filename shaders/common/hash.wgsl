// Hashes shared by the Lipp kernels and the roofline passes. Composed with
// naga_oil:
//   #import strandgraph::hash::pcg
#define_import_path strandgraph::hash

// PCG hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT
// 2020), as bench::pcg, which the CPU kernels use.
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
