//! The graph file format: what a `.ron` graph declares.
//!
//! ```ron
//! Graph(
//!     name: "example",
//!     resources: [
//!         Buffer(name: "groom.positions", size: PerElement(Vertices, 16), lifetime: Imported),
//!         Buffer(name: "clip_positions", size: PerElement(Vertices, 16)),
//!         Image(name: "output", format: Rgba16Float, size: Screen, lifetime: Imported),
//!     ],
//!     passes: [
//!         Pass(name: "skin", kind: "kulikov.skin", reads: ["groom.positions"], writes: ["clip_positions"]),
//!         Pass(name: "compose", kind: "kulikov.compose", reads: ["clip_positions"], writes: ["color:output"]),
//!     ],
//!     outputs: ["output"],
//! )
//! ```
//!
//! Access entries are resource names with an optional usage prefix
//! (`"indirect:raster_args"`, `"color:output"`); see [`Usage`]. A suffix
//! `as NAME` (`"indirect:shadow_args as raster_args"`) hands the resource to
//! the pass's kernel under the binding name `NAME`, so one kind can run on
//! two sets of resources. Sizes that
//! depend on the scene are symbolic ([`Quantity`]) and resolved when a plan is
//! instantiated.

use serde::{Deserialize, Serialize};

/// A whole graph file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(rename = "Graph", deny_unknown_fields)]
pub struct GraphDesc {
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub resources: Vec<ResourceDecl>,
    pub passes: Vec<PassDecl>,
    /// Resources the frame must produce; passes that feed none of them are culled.
    pub outputs: Vec<String>,
}

/// A buffer or image the graph's passes share.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub enum ResourceDecl {
    Buffer {
        name: String,
        size: BufferSize,
        #[serde(default)]
        lifetime: LifetimeClass,
    },
    Image {
        name: String,
        format: ImageFormat,
        size: ImageSize,
        #[serde(default = "one")]
        layers: u32,
        /// Samples per texel: 1, or 2, 4 or 8 for a multisampled attachment
        /// (only attachment usages may touch it; the draws that render into
        /// it rasterize with that many samples).
        #[serde(default = "one")]
        samples: u32,
        #[serde(default)]
        lifetime: LifetimeClass,
    },
}

fn one() -> u32 {
    1
}

impl ResourceDecl {
    pub fn name(&self) -> &str {
        match self {
            ResourceDecl::Buffer { name, .. } | ResourceDecl::Image { name, .. } => name,
        }
    }
    pub fn lifetime(&self) -> LifetimeClass {
        match self {
            ResourceDecl::Buffer { lifetime, .. } | ResourceDecl::Image { lifetime, .. } => {
                *lifetime
            }
        }
    }
    pub fn is_image(&self) -> bool {
        matches!(self, ResourceDecl::Image { .. })
    }
    /// Samples per texel: 1 for buffers and single-sampled images.
    pub fn samples(&self) -> u32 {
        match self {
            ResourceDecl::Image { samples, .. } => *samples,
            ResourceDecl::Buffer { .. } => 1,
        }
    }
}

/// Who owns a resource's memory and how long its contents matter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Deserialize, Serialize)]
pub enum LifetimeClass {
    /// Lives from its first to its last use in the frame; may share memory.
    #[default]
    Transient,
    /// Owned outside the graph (groom data, scene depth, the output image).
    Imported,
    /// Persists into the next frame: readers see the previous frame's contents.
    History,
}

/// A scene quantity that sizes resources; resolved at instantiation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, Serialize)]
pub enum Quantity {
    Strands,
    Vertices,
    Segments,
    /// Hair-mesh bundles (Lipp §2).
    Bundles,
    /// Strands the hair meshes generate: Σ N over bundles (Lipp §2).
    MeshStrands,
    /// Hair models (grooms) in the scene.
    Models,
    /// Hair patches: textured ribbon strips built from the grooms
    /// (Scheuermann 2004's polygonal hair model).
    Patches,
    /// Triangles of the scene's meshes (heads, bodies).
    Triangles,
    Lights,
    /// Screen pixels (width × height).
    Pixels,
    /// Screen tiles of the given edge length in pixels.
    Tiles(u32),
}

impl Quantity {
    /// Scene content a scene may lack: meshes (a groom with no head),
    /// hair meshes, hair patches (built only for the graphs that draw them), lights. Buffers sized by these hold at least one element
    /// so their bindings stay valid; passes count from the quantities, never
    /// from a buffer's length, so the placeholder is never read as content.
    pub fn may_be_empty(self) -> bool {
        matches!(
            self,
            Quantity::Triangles
                | Quantity::Bundles
                | Quantity::MeshStrands
                | Quantity::Patches
                | Quantity::Lights
        )
    }
}

/// How many bytes a buffer holds.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
pub enum BufferSize {
    /// A fixed size.
    Bytes(u64),
    /// `bytes` per element of a scene quantity.
    PerElement(Quantity, u64),
    /// One bit per element, rounded up to whole 32-bit words (visibility masks).
    Bits(Quantity),
    /// `bytes` per element of a quantity plus a fixed header (counters, dispatch arguments).
    PerElementPlus(Quantity, u64, u64),
    /// An atlas of square tiles: `tiles` tiles of `tile`×`tile` texels, `layers` deep.
    /// Kulikov: "tiled visibility atlas, 64x64 pixel tiles ... 2 million pixels, 32 MB".
    Atlas {
        tile: u32,
        tiles: u32,
        layers: u32,
        texel_bytes: u32,
    },
    /// `PerElementPlus(quantity, per, header)` capped at `at_most` bytes:
    /// room that grows with the scene but stays bindable (2^27 bytes, 128
    /// MiB, is Vulkan's least maxStorageBufferRange: lavapipe's, and wgpu's
    /// default). A pass that binds it derives what it holds from its size.
    Capped {
        quantity: Quantity,
        per: u64,
        header: u64,
        at_most: u64,
    },
}

/// How large an image is.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
pub enum ImageSize {
    /// The output resolution.
    Screen,
    /// The output resolution divided by `n` on each axis, rounded up.
    ScreenDiv(u32),
    Fixed(u32, u32),
}

/// Texel formats. Names follow WGSL/Vulkan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, Serialize)]
pub enum ImageFormat {
    R8Unorm,
    Rgba8Unorm,
    Rgba8Srgb,
    R16Float,
    Rg16Float,
    Rgba16Float,
    R32Float,
    R32Uint,
    Rg32Uint,
    Rgba32Float,
    D32Float,
}

impl ImageFormat {
    pub fn texel_bytes(self) -> u64 {
        use ImageFormat::*;
        match self {
            R8Unorm => 1,
            R16Float => 2,
            Rgba8Unorm | Rgba8Srgb | Rg16Float | R32Float | R32Uint | D32Float => 4,
            Rg32Uint | Rgba16Float => 8,
            Rgba32Float => 16,
        }
    }
    pub fn is_depth(self) -> bool {
        self == ImageFormat::D32Float
    }
}

/// The queue a pass prefers.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default, Deserialize, Serialize,
)]
pub enum Queue {
    #[default]
    Graphics,
    AsyncCompute,
    Transfer,
}

impl Queue {
    pub const ALL: [Queue; 3] = [Queue::Graphics, Queue::AsyncCompute, Queue::Transfer];
}

impl std::fmt::Display for Queue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Queue::Graphics => "graphics",
            Queue::AsyncCompute => "async-compute",
            Queue::Transfer => "transfer",
        })
    }
}

/// One node of the graph.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(rename = "Pass", deny_unknown_fields)]
pub struct PassDecl {
    pub name: String,
    /// Key into the pass registry, e.g. `"kulikov.raster"`.
    pub kind: String,
    #[serde(default)]
    pub queue: Queue,
    /// Handed to the pass unchanged; the pass's own parameter struct reads it.
    #[serde(default = "empty_map")]
    pub params: ron::Value,
    #[serde(default)]
    pub reads: Vec<String>,
    #[serde(default)]
    pub writes: Vec<String>,
    /// Read-modify-write with commutative atomics (`atomicMin`, `atomicAdd`).
    #[serde(default)]
    pub atomics: Vec<String>,
    /// Run this pass once per hair model (see [`Repeat`]).
    #[serde(default)]
    pub repeat: Repeat,
    /// Compile this pass's shader with naga's loop counters even where the
    /// backend leaves them out (docs/architecture.md, "Shaders"): a kernel
    /// whose loops the driver unrolls into more registers than they save.
    #[serde(default)]
    pub loop_bounding: bool,
}

/// How often a pass runs per frame.
///
/// Consecutive `PerModel` passes form one block that runs once per hair
/// model, model after model (Lipp §3.5 "Multiple Grooms": "each groom is
/// processed sequentially through the same rasterization and filtering
/// pipeline"). The compiler unrolls the block for the scene's model count
/// ([`crate::unroll`]): each copy gets the param `model_index`, transients
/// only the block uses get one copy per model (which the memory plan
/// aliases), and an in-place write `a -> b` in the block chains from one
/// model to the next.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
pub enum Repeat {
    #[default]
    Once,
    PerModel,
}

fn empty_map() -> ron::Value {
    ron::Value::Map(ron::Map::new())
}

/// How a pass touches a resource.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, Serialize)]
pub enum AccessMode {
    Read,
    Write,
    Atomic,
}

impl AccessMode {
    pub fn writes(self) -> bool {
        self != AccessMode::Read
    }
    /// The list a graph file declares this access in.
    pub fn field(self) -> &'static str {
        match self {
            AccessMode::Read => "reads",
            AccessMode::Write => "writes",
            AccessMode::Atomic => "atomics",
        }
    }
}

/// The hardware path an access goes through; written as a prefix of the
/// resource name in access lists (`"sampled:scene.depth"`). No prefix means
/// `storage`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, Serialize)]
pub enum Usage {
    /// Storage buffer or storage image (the default).
    Storage,
    Uniform,
    /// Sampled image.
    Sampled,
    /// Indirect dispatch or draw arguments.
    Indirect,
    /// Colour attachment of a raster pass (writes blend, so they also read).
    Color,
    /// Depth attachment: `reads` tests only, `writes` tests and writes.
    Depth,
    /// Copy source (`reads`) or destination (`writes`).
    Copy,
}

impl Usage {
    pub const PREFIXES: [(&'static str, Usage); 7] = [
        ("storage", Usage::Storage),
        ("uniform", Usage::Uniform),
        ("sampled", Usage::Sampled),
        ("indirect", Usage::Indirect),
        ("color", Usage::Color),
        ("depth", Usage::Depth),
        ("copy", Usage::Copy),
    ];

    pub fn prefix(self) -> &'static str {
        Usage::PREFIXES
            .iter()
            .find(|(_, u)| *u == self)
            .map_or("storage", |(p, _)| p)
    }

    /// Usages that only images support.
    pub fn image_only(self) -> bool {
        matches!(self, Usage::Sampled | Usage::Color | Usage::Depth)
    }

    /// Usages that only buffers support.
    pub fn buffer_only(self) -> bool {
        matches!(self, Usage::Uniform | Usage::Indirect)
    }

    /// Whether a queue of this kind can perform the access.
    /// Compute queues have no rasterizer; transfer queues only copy.
    pub fn allowed_on(self, queue: Queue) -> bool {
        match queue {
            Queue::Graphics => true,
            Queue::AsyncCompute => !matches!(self, Usage::Color | Usage::Depth),
            Queue::Transfer => self == Usage::Copy,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_resource_shape() {
        let src = r#"Graph(
            name: "g",
            resources: [
                Buffer(name: "a", size: Bytes(16)),
                Buffer(name: "b", size: PerElement(Tiles(64), 4), lifetime: History),
                Buffer(name: "c", size: PerElementPlus(Segments, 4, 16)),
                Buffer(name: "d", size: Atlas(tile: 64, tiles: 512, layers: 4, texel_bytes: 4)),
                Image(name: "e", format: D32Float, size: ScreenDiv(16), lifetime: Imported),
                Image(name: "f", format: Rgba16Float, size: Fixed(8, 8), layers: 2),
                Buffer(name: "g", size: Capped(quantity: Strands, per: 12, header: 16, at_most: 4096)),
            ],
            passes: [Pass(name: "p", kind: "k", queue: AsyncCompute, params: {"x": 1})],
            outputs: [],
        )"#;
        let g: GraphDesc = ron::from_str(src).unwrap();
        assert_eq!(g.resources.len(), 7);
        assert_eq!(g.resources[1].lifetime(), LifetimeClass::History);
        assert!(g.resources[5].is_image());
        assert_eq!(g.passes[0].queue, Queue::AsyncCompute);
    }

    #[test]
    fn queue_capabilities() {
        assert!(Usage::Color.allowed_on(Queue::Graphics));
        assert!(!Usage::Color.allowed_on(Queue::AsyncCompute));
        assert!(Usage::Indirect.allowed_on(Queue::AsyncCompute));
        assert!(!Usage::Storage.allowed_on(Queue::Transfer));
        assert!(Usage::Copy.allowed_on(Queue::Transfer));
    }
}
