// bench.copy: roofline reference for bandwidth, a buffer-to-buffer copy in
// a compute shader (one vec4 per invocation), as roofline.rs `CopyKernel`.

struct CopyParams {
    unused0: u32,
    unused1: u32,
}

@group(0) @binding(0) var<uniform> params: CopyParams;
@group(0) @binding(1) var<storage, read> copy_src: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> copy_dst: array<vec4<u32>>;

@compute @workgroup_size(256)
fn copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Binding 0 is part of the pass contract even where nothing is read from it.
    _ = params.unused0;
    let n = min(arrayLength(&copy_src), arrayLength(&copy_dst));
    // Past 65,535 workgroups (Dispatch::CoverWrites) the lanes stride.
    for (var i = gid.x; i < n; i += groups.x * 256u) {
        copy_dst[i] = copy_src[i];
    }
}
