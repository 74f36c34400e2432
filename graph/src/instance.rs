//! Instantiation: symbolic sizes resolved against a scene's quantities, then
//! the memory plan.

use crate::alias::{AliasRequest, Aliasing, HeapKind, MemoryPlan, plan_memory, plan_memory_with};
use crate::error::{ErrorKind, GraphError, GraphErrors};
use crate::plan::Plan;
use crate::reach::Reach;
use crate::schema::{BufferSize, ImageSize, Quantity, ResourceDecl};
use serde::{Deserialize, Serialize};

/// The scene quantities graph sizes refer to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Quantities {
    pub strands: u64,
    pub vertices: u64,
    pub segments: u64,
    pub bundles: u64,
    /// Σ N over the hair meshes' bundles.
    pub mesh_strands: u64,
    pub models: u64,
    pub patches: u64,
    pub triangles: u64,
    pub lights: u64,
    pub width: u32,
    pub height: u32,
}

impl Quantities {
    /// A stand-in for a showcase-sized scene when no scene is given: one
    /// 130k-strand, 32-point groom (Lipp's evaluation size) plus two small
    /// facial-hair models, at 1080p with three lights.
    pub fn example() -> Self {
        let strands = 130_000 + 2 * 4_000;
        let points = 32;
        Self {
            strands,
            vertices: strands * points,
            segments: strands * (points - 1),
            bundles: 4_096,
            mesh_strands: 130_000,
            models: 3,
            // One per 48 strands, three layers (PatchParams' defaults).
            patches: strands / 48 * 3,
            triangles: 20_000,
            lights: 3,
            width: 1920,
            height: 1080,
        }
    }

    pub fn count(&self, q: Quantity) -> u64 {
        let (w, h) = (u64::from(self.width), u64::from(self.height));
        match q {
            Quantity::Strands => self.strands,
            Quantity::Vertices => self.vertices,
            Quantity::Segments => self.segments,
            Quantity::Bundles => self.bundles,
            Quantity::MeshStrands => self.mesh_strands,
            Quantity::Models => self.models,
            Quantity::Patches => self.patches,
            Quantity::Triangles => self.triangles,
            Quantity::Lights => self.lights,
            Quantity::Pixels => w * h,
            Quantity::Tiles(t) => {
                let t = u64::from(t.max(1));
                w.div_ceil(t) * h.div_ceil(t)
            }
        }
    }
}

/// A resource's concrete size.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ResourceSize {
    pub bytes: u64,
    /// Width, height and layers, for images.
    pub extent: Option<[u32; 3]>,
}

/// A plan made concrete for one scene.
#[derive(Debug, Clone, Serialize)]
pub struct Instance {
    pub quantities: Quantities,
    /// Indexed by resource id.
    pub sizes: Vec<ResourceSize>,
    pub memory: MemoryPlan,
}

impl Plan {
    /// Resolves every size and plans transient memory.
    pub fn instantiate(&self, q: &Quantities) -> Result<Instance, GraphErrors> {
        let mut sizes = Vec::new();
        let mut errors = Vec::new();
        for res in &self.graph.resources {
            match resolve_size(&res.decl, q) {
                Ok(s) => sizes.push(s),
                Err(why) => {
                    errors.push(GraphError::new(
                        ErrorKind::Size,
                        &self.graph.source,
                        res.span,
                        format!("resource `{}`: {why}", res.name),
                    ));
                    sizes.push(ResourceSize {
                        bytes: 0,
                        extent: None,
                    });
                }
            }
        }
        if !errors.is_empty() {
            return Err(GraphErrors(errors));
        }
        let requests: Vec<AliasRequest> = self
            .lifetimes
            .iter()
            .map(|l| {
                let heap = if self.graph.resources[l.resource].decl.is_image() {
                    HeapKind::Images
                } else {
                    HeapKind::Buffers
                };
                AliasRequest {
                    resource: l.resource,
                    heap,
                    size: sizes[l.resource].bytes,
                    alignment: heap.default_alignment(),
                    first: l.first,
                    end: l.end,
                }
            })
            .collect();
        Ok(Instance {
            quantities: *q,
            memory: self.plan_memory(&requests),
            sizes,
        })
    }

    /// Transients placed by [`Plan::aliasing`].
    pub fn plan_memory(&self, requests: &[AliasRequest]) -> MemoryPlan {
        match self.aliasing {
            Aliasing::FirstFit => plan_memory(requests),
            Aliasing::NoNewWaits => plan_memory_with(requests, &self.reuse_adds_no_wait()),
        }
    }

    /// `(earlier, later)`: whether transient `later` can take `earlier`'s
    /// bytes without a wait the plan's dependencies do not already make:
    /// every pass that uses `earlier` comes before `later`'s first user
    /// through them. A backend hands the bytes over with a barrier that
    /// makes that first user wait for those passes ([`Aliasing::NoNewWaits`]).
    pub fn reuse_adds_no_wait(&self) -> impl Fn(usize, usize) -> bool + '_ {
        let edges = self.dependencies.iter().map(|d| (d.from, d.to));
        let reach = Reach::new(self.graph.passes.len(), &self.order, edges);
        let lifetime = |r: usize| self.lifetimes.iter().find(|l| l.resource == r);
        move |earlier, later| match (lifetime(earlier), lifetime(later)) {
            (Some(a), Some(b)) => {
                let first = self.order[b.first];
                a.uses.iter().all(|&(u, _)| reach.reaches(u, first))
            }
            _ => true,
        }
    }
}

fn resolve_size(decl: &ResourceDecl, q: &Quantities) -> Result<ResourceSize, String> {
    let overflow = || "size overflows 64 bits".to_string();
    // Optional content (no head mesh, no hair mesh) keeps one placeholder
    // element (see `Quantity::may_be_empty`); anything else at zero is an error below.
    let elements = |quantity: Quantity| {
        let n = q.count(quantity);
        if quantity.may_be_empty() { n.max(1) } else { n }
    };
    let size = match decl {
        ResourceDecl::Buffer { size, .. } => {
            let bytes = match *size {
                BufferSize::Bytes(b) => b,
                BufferSize::PerElement(quantity, per) => {
                    elements(quantity).checked_mul(per).ok_or_else(overflow)?
                }
                BufferSize::Bits(quantity) => elements(quantity).div_ceil(32) * 4,
                BufferSize::PerElementPlus(quantity, per, extra) => elements(quantity)
                    .checked_mul(per)
                    .and_then(|b| b.checked_add(extra))
                    .ok_or_else(overflow)?,
                BufferSize::Capped {
                    quantity,
                    per,
                    header,
                    at_most,
                } => elements(quantity)
                    .checked_mul(per)
                    .and_then(|b| b.checked_add(header))
                    .map_or(at_most, |b| b.min(at_most)),
                BufferSize::Atlas {
                    tile,
                    tiles,
                    layers,
                    texel_bytes,
                } => [
                    u64::from(tile),
                    u64::from(tile),
                    u64::from(tiles),
                    u64::from(layers),
                    u64::from(texel_bytes),
                ]
                .into_iter()
                .try_fold(1u64, u64::checked_mul)
                .ok_or_else(overflow)?,
            };
            ResourceSize {
                bytes,
                extent: None,
            }
        }
        ResourceDecl::Image {
            format,
            size,
            layers,
            samples,
            ..
        } => {
            let (w, h) = match *size {
                ImageSize::Screen => (q.width, q.height),
                ImageSize::ScreenDiv(0) => return Err("ScreenDiv(0) divides by zero".into()),
                ImageSize::ScreenDiv(d) => (q.width.div_ceil(d), q.height.div_ceil(d)),
                ImageSize::Fixed(w, h) => (w, h),
            };
            let bytes = [
                u64::from(w),
                u64::from(h),
                u64::from(*layers),
                u64::from(*samples),
                format.texel_bytes(),
            ]
            .into_iter()
            .try_fold(1u64, u64::checked_mul)
            .ok_or_else(overflow)?;
            ResourceSize {
                bytes,
                extent: Some([w, h, *layers]),
            }
        }
    };
    if size.bytes == 0 {
        return Err(format!(
            "size is zero bytes for this scene ({})",
            describe(decl)
        ));
    }
    Ok(size)
}

fn describe(decl: &ResourceDecl) -> String {
    match decl {
        ResourceDecl::Buffer { size, .. } => format!("{size:?}"),
        ResourceDecl::Image { size, .. } => format!("{size:?}"),
    }
}
