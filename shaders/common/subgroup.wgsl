// Subgroup helpers WGSL lacks, shared by every pass that aggregates atomics
// per subgroup. Composed with naga_oil:
//   #import strandgraph::subgroup::elected
// A module of its own (not in a pipeline's common module) so that only the
// shaders that import it need the SUBGROUP capability.
#define_import_path strandgraph::subgroup

// subgroupElect: the lowest active lane of the ballot, the lane the CPU
// kernels elect (kernel::subgroup::elect).
fn elected(lane: u32) -> bool {
    let ballot = subgroupBallot(true);
    var first = 0u;
    for (var k = 0u; k < 4u; k++) {
        if ballot[k] != 0u {
            first = 32u * k + firstTrailingBit(ballot[k]);
            break;
        }
    }
    return lane == first;
}
