//! `kulikov.tile_alloc`: 64×64 atlas tiles for each model's visible screen bounds.
//!
//! Kulikov, "Visibility buffer: tile allocation, downscale": "Each hair piece
//! allocates tiles from the atlas based on its screen-space boundaries ...
//! Skip allocation if all segments are culled ... Downscale resolution for
//! each tile until everything fits." The atlas holds 2M pixels (512 tiles).

use super::TILE;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::params::{Invalid, PassParams, in_range};

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TileParams {
    /// Atlas capacity in tiles (Kulikov: 2M pixels, 512 tiles).
    pub atlas_tiles: u32,
    /// "Downscale resolution for each tile until everything fits", at most this far.
    pub max_downscale: u32,
    /// Only 64: the atlas layout is built for it.
    pub tile_size: u32,
}

impl Default for TileParams {
    fn default() -> Self {
        Self {
            atlas_tiles: 512,
            max_downscale: 8,
            tile_size: TILE,
        }
    }
}

impl PassParams for TileParams {
    fn validate(&self) -> Result<(), Invalid> {
        if self.tile_size != TILE {
            return Err(Invalid::new(
                "tile_size",
                format!("the atlas layout is built for {TILE}x{TILE} tiles"),
            ));
        }
        in_range("max_downscale", self.max_downscale, 1..=u32::MAX)
    }
}

crate::gpu_block! {
    /// `TileParams`: atlas tiles, max downscale, hair models.
    pub struct TileGpu {
        atlas_tiles: u32,
        max_downscale: u32,
        /// Scene quantity: hair models.
        models: u32,
    }
}

pub static TILE_ALLOC: PassKind<TileParams, TileGpu> = PassKind {
    kind: "kulikov.tile_alloc",
    summary: "allocate 64x64 atlas tiles per model from screen bounds, downscaling until they fit",
    source: "Kulikov 2025, 'Visibility buffer: tile allocation, downscale'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("screen_bounds"),
        Binding::write("atlas_tiles"),
    ]),
    workgroup_size: 1,
    dispatch: Dispatch::Fixed(1),
    shader: Shader::compute("kulikov/tile_alloc.wgsl", "allocate"),
    kernel: |p| {
        Box::new(AllocKernel {
            atlas_tiles: p.atlas_tiles,
            max_downscale: p.max_downscale,
        })
    },
    gpu: |p, q| TileGpu {
        atlas_tiles: p.atlas_tiles,
        max_downscale: p.max_downscale,
        models: count(q.models),
    },
    raster: None,
};

/// One model's part of the atlas (`atlas_tiles`, 8 words per model).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ModelTiles {
    pub first_tile: u32,
    pub grid_w: u32,
    pub grid_h: u32,
    /// Grid origin in tiles of `TILE × downscale` screen pixels.
    pub origin_x: u32,
    pub origin_y: u32,
    pub downscale: u32,
    /// 0 when the model has nothing visible or did not fit.
    pub valid: u32,
}

impl ModelTiles {
    pub const WORDS: usize = 8;
    pub fn load(w: &Words<'_>, m: usize) -> Self {
        let b = m * Self::WORDS;
        Self {
            first_tile: w.load(b),
            grid_w: w.load(b + 1),
            grid_h: w.load(b + 2),
            origin_x: w.load(b + 3),
            origin_y: w.load(b + 4),
            downscale: w.load(b + 5).max(1),
            valid: w.load(b + 6),
        }
    }
    fn store(&self, w: &Words<'_>, m: usize) {
        let b = m * Self::WORDS;
        for (i, v) in [
            self.first_tile,
            self.grid_w,
            self.grid_h,
            self.origin_x,
            self.origin_y,
            self.downscale,
            self.valid,
            0,
        ]
        .into_iter()
        .enumerate()
        {
            w.store(b + i, v);
        }
    }
    pub fn tiles(&self) -> u32 {
        self.grid_w * self.grid_h
    }
    /// Atlas texel of screen pixel (x, y), if this model's tiles cover it.
    pub fn texel(&self, x: u32, y: u32) -> Option<u32> {
        if self.valid == 0 {
            return None;
        }
        let (u, v) = (x / self.downscale, y / self.downscale);
        let (u, v) = (
            u.checked_sub(self.origin_x * TILE)?,
            v.checked_sub(self.origin_y * TILE)?,
        );
        let (tx, ty) = (u / TILE, v / TILE);
        if tx >= self.grid_w || ty >= self.grid_h {
            return None;
        }
        Some((self.first_tile + ty * self.grid_w + tx) * TILE * TILE + (v % TILE) * TILE + u % TILE)
    }
}

/// Visible screen bounds of model `m` as the cull pass left them, if any.
pub fn visible_bounds(bounds: &Words<'_>, m: usize) -> Option<[u32; 4]> {
    let b = [
        bounds.load(4 * m),
        bounds.load(4 * m + 1),
        !bounds.load(4 * m + 2),
        !bounds.load(4 * m + 3),
    ];
    (b[0] <= b[2] && b[1] <= b[3]).then_some(b)
}

/// Allocates every model at the smallest power-of-two downscale that fits.
pub fn allocate(
    bounds: &[Option<[u32; 4]>],
    atlas_tiles: u32,
    max_downscale: u32,
) -> Vec<ModelTiles> {
    let grid = |b: [u32; 4], d: u32| {
        let span = TILE * d;
        (
            b[0] / span,
            b[1] / span,
            b[2] / span - b[0] / span + 1,
            b[3] / span - b[1] / span + 1,
        )
    };
    let mut d = 1;
    loop {
        let need: u32 = bounds
            .iter()
            .flatten()
            .map(|&b| grid(b, d).2 * grid(b, d).3)
            .sum();
        if need <= atlas_tiles || d >= max_downscale {
            break;
        }
        d *= 2;
    }
    let mut next = 0;
    bounds
        .iter()
        .map(|b| {
            let Some(b) = *b else {
                return ModelTiles {
                    downscale: d,
                    ..Default::default()
                };
            };
            let (ox, oy, gw, gh) = grid(b, d);
            let fits = next + gw * gh <= atlas_tiles;
            let t = ModelTiles {
                first_tile: next,
                grid_w: gw,
                grid_h: gh,
                origin_x: ox,
                origin_y: oy,
                downscale: d,
                valid: u32::from(fits),
            };
            if fits {
                next += gw * gh;
            }
            t
        })
        .collect()
}

struct AllocKernel {
    atlas_tiles: u32,
    max_downscale: u32,
}

impl CpuKernel for AllocKernel {
    fn run_workgroup(&self, _: u32, ctx: &Ctx<'_>) {
        let models = ctx.quantities.models as usize;
        let bounds_w = ctx.words("screen_bounds");
        let bounds: Vec<_> = (0..models).map(|m| visible_bounds(&bounds_w, m)).collect();
        let out = ctx.words("atlas_tiles");
        for (m, t) in allocate(&bounds, self.atlas_tiles, self.max_downscale)
            .iter()
            .enumerate()
        {
            t.store(&out, m);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_at_full_resolution_when_there_is_room() {
        let t = allocate(&[Some([0, 0, 639, 319]), None], 512, 8);
        assert_eq!(
            (t[0].grid_w, t[0].grid_h, t[0].downscale, t[0].valid),
            (10, 5, 1, 1)
        );
        assert_eq!(t[1].valid, 0, "no allocation when every segment was culled");
        assert_eq!(t[0].texel(65, 2), Some(TILE * TILE + 2 * TILE + 1));
    }

    #[test]
    fn over_budget_scene_falls_back_to_half_resolution_and_fits() {
        // Two overlapping full-HD models need 2 × 510 tiles at full resolution.
        let full_hd = Some([0, 0, 1919, 1079]);
        let t = allocate(&[full_hd, full_hd], 512, 8);
        assert!(t.iter().all(|m| m.downscale == 2 && m.valid == 1), "{t:?}");
        assert!(t.iter().map(ModelTiles::tiles).sum::<u32>() <= 512);
        assert_eq!(t[1].first_tile, t[0].tiles(), "models get separate tiles");
        // Pixel (1919, 1079) maps into the second model's last tile.
        let last = t[1].texel(1919, 1079).unwrap();
        assert!(last < 512 * TILE * TILE && last >= t[1].first_tile * TILE * TILE);
    }
}
