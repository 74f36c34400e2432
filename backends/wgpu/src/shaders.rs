//! Which wgpu feature each naga capability needs. Composition itself is
//! shared with the other backends: [`strandgraph_passes::wgsl`].

use naga::valid::Capabilities;

/// wgpu-core derives a device's naga capabilities from its features
/// (wgpu-core 30 `device/resource.rs`, `create_validator`): `SUBGROUP` gives
/// `SUBGROUP`, `SUBGROUP_BARRIER` gives `SUBGROUP_BARRIER`, `SHADER_F64`
/// gives `FLOAT64`, `SHADER_EARLY_DEPTH_TEST` gives `EARLY_DEPTH_TEST`
/// (`MULTISAMPLED_SHADING` is no feature: the downlevel flag of that name,
/// which every Vulkan adapter with sampleRateShading has, gives it), `SHADER_INT64` gives `SHADER_INT64`, and the two int64
/// atomic features give their capabilities; `EXPERIMENTAL_MESH_SHADER`
/// gives `MESH_SHADER` (and needs the device's experimental-features
/// token, `session.rs`).
pub const CAPABILITY_FEATURES: [(Capabilities, wgpu::Features, &str); 8] = [
    (
        Capabilities::MESH_SHADER,
        wgpu::Features::EXPERIMENTAL_MESH_SHADER,
        "EXPERIMENTAL_MESH_SHADER",
    ),
    (
        Capabilities::EARLY_DEPTH_TEST,
        wgpu::Features::SHADER_EARLY_DEPTH_TEST,
        "SHADER_EARLY_DEPTH_TEST",
    ),
    (Capabilities::SUBGROUP, wgpu::Features::SUBGROUP, "SUBGROUP"),
    (
        Capabilities::SUBGROUP_BARRIER,
        wgpu::Features::SUBGROUP_BARRIER,
        "SUBGROUP_BARRIER",
    ),
    (
        Capabilities::FLOAT64,
        wgpu::Features::SHADER_F64,
        "SHADER_F64",
    ),
    (
        Capabilities::SHADER_INT64,
        wgpu::Features::SHADER_INT64,
        "SHADER_INT64",
    ),
    (
        Capabilities::SHADER_INT64_ATOMIC_MIN_MAX,
        wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
        "SHADER_INT64_ATOMIC_MIN_MAX",
    ),
    (
        Capabilities::SHADER_INT64_ATOMIC_ALL_OPS,
        wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS,
        "SHADER_INT64_ATOMIC_ALL_OPS",
    ),
];

#[cfg(test)]
mod tests {
    /// ... except `MULTISAMPLED_SHADING`, which wgpu grants from a
    /// downlevel flag, not a feature (see above).
    #[test]
    fn every_shared_capability_has_a_feature() {
        use naga::valid::Capabilities;
        for cap in strandgraph_passes::wgsl::CAPABILITIES {
            if cap == Capabilities::MULTISAMPLED_SHADING {
                continue;
            }
            assert!(
                super::CAPABILITY_FEATURES.iter().any(|(c, _, _)| *c == cap),
                "{cap:?} has no wgpu feature"
            );
        }
    }
}
