//! The CPU kernel of `scheuermann.hair` on patches built by hand: depth
//! test, culling, alpha test and blending in draw order.

use super::hair::{BACK_FACES, FRONT_FACES, HairParams, OPAQUE, PRIME_DEPTH, SEGMENTS};
use super::shading::{Surface, hair_lighting};
use super::upload::Placement;
use crate::contract::PassDef;
use crate::kernel::harness::Harness;
use crate::kulikov::debug_resolve::load_rgba16f;
use crate::layout::{LightData, ModelData, words_of};
use crate::opaque_mesh::testing::{frame, run_with, sun};
use glam::{Mat4, Vec3, Vec4};
use strandgraph_assets::hairpatch::{HairTexture, PatchVertex};
use strandgraph_graph::Quantities;

const W: u32 = 32;
const H: u32 = 32;

/// A flat strip in the plane z = `z`, facing +z (the camera) when `facing`,
/// 0.2 wide and 0.4 tall around the origin, root at the bottom.
fn strip(z: f32, facing: bool) -> Vec<u32> {
    let place = Placement::new(Mat4::IDENTITY);
    let n = if facing { Vec3::Z } else { Vec3::NEG_Z };
    // Right = centre + cross(t, n) · w/2: +x facing the camera, −x away.
    let right = Vec3::Y.cross(n);
    let mut words = Vec::new();
    for i in 0..=SEGMENTS {
        let v = i as f32 / SEGMENTS as f32;
        let centre = Vec3::new(0.0, -0.2 + 0.4 * v, z);
        for (side, u) in [(-0.1f32, 0.3f32), (0.1, 0.45)] {
            words.extend(place.vertex(&PatchVertex {
                position: centre + right * side,
                tangent: Vec3::Y,
                normal: n,
                u,
                v,
                ao: 1.0,
                texels_per_metre: 1.0,
            }));
        }
    }
    words
}

/// Every texel: base 1, the given alpha, shift 0.5, no sparkle.
fn texture(alpha: u8) -> Vec<u32> {
    let texels = HairTexture::level_offset(HairTexture::LEVELS);
    vec![u32::from_le_bytes([255, alpha, 128, 0]); texels]
}

fn model(colour: [f32; 3]) -> ModelData {
    ModelData {
        color: [colour[0], colour[1], colour[2], 0.3],
        ..bytemuck::Zeroable::zeroed()
    }
}

const RED: [f32; 3] = [0.5, 0.1, 0.05];
const BLUE: [f32; 3] = [0.05, 0.1, 0.5];

/// Patches (drawn in the given order, with their models) over a grey
/// background, in front of a far depth buffer.
fn harness(patches: &[(Vec<u32>, u32)], alpha: u8) -> Harness {
    let mut f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, W, H);
    f.light_count = 1;
    let mut hs = Harness::new(Quantities {
        patches: patches.len() as u64,
        models: 2,
        lights: 1,
        width: W,
        height: H,
        ..Default::default()
    });
    let grey = half::f16::from_f32(0.2).to_bits() as u32;
    let one = half::f16::from_f32(1.0).to_bits() as u32;
    hs.buffer("frame", words_of(&[f]))
        .buffer("models", words_of(&[model(RED), model(BLUE)]))
        .buffer("lights", words_of(&[light()]))
        .buffer(
            "patches.vertices",
            patches.iter().flat_map(|p| p.0.clone()).collect(),
        )
        .buffer("patches.models", patches.iter().map(|p| p.1).collect())
        .buffer("patches.texture", texture(alpha))
        .buffer(
            "output",
            [grey | grey << 16, grey | one << 16].repeat((W * H) as usize),
        )
        .buffer("depth_buffer", vec![1.0f32.to_bits(); (W * H) as usize]);
    hs
}

/// The background, as the Rgba16Float attachment holds it.
fn grey() -> Vec3 {
    Vec3::splat(half::f16::from_f32(0.2).to_f32())
}

fn light() -> LightData {
    sun(Vec3::new(0.3, -0.4, -1.0), 2.0)
}

fn stage(hs: &Harness, name: &str) {
    let def: &dyn PassDef = match name {
        "PrimeDepth" => &PRIME_DEPTH,
        "Opaque" => &OPAQUE,
        "BackFaces" => &BACK_FACES,
        _ => &FRONT_FACES,
    };
    run_with(hs, def, &ron::Value::Unit);
    assert_eq!(hs.out_of_bounds(), 0);
}

fn centre(hs: &Harness) -> Vec4 {
    let out = hs.read("output");
    let words: Vec<std::sync::atomic::AtomicU32> = out
        .into_iter()
        .map(std::sync::atomic::AtomicU32::new)
        .collect();
    let oob = std::sync::atomic::AtomicU64::new(0);
    let w = crate::kernel::Words::new(&words, &oob);
    Vec4::from(load_rgba16f(&w, (H / 2 * W + W / 2) as usize))
}

/// Where the centre pixel's ray meets the plane z.
fn centre_point(z: f32) -> Vec3 {
    let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, W, H);
    let inv = Mat4::from_cols_array(&f.inv_view_proj);
    let ndc = |s: u32, n: u32| (s / 2) as f32 / n as f32 * 2.0 - 1.0 + 1.0 / n as f32;
    let (x, y) = (ndc(W, W), -ndc(H, H));
    let near = inv.project_point3(Vec3::new(x, y, 0.0));
    let far = inv.project_point3(Vec3::new(x, y, 1.0));
    near + (far - near) * ((z - near.z) / (far.z - near.z))
}

/// What the shading gives the strip at z at the centre pixel.
fn lit(colour: [f32; 3], z: f32, alpha: f32) -> Vec4 {
    let p = HairParams::default();
    let at = Surface {
        world: centre_point(z),
        tangent: Vec3::Y,
        normal: Vec3::Z,
        ao: 1.0,
    };
    let tex = Vec4::new(1.0, alpha, 128.0 / 255.0, 0.0);
    hair_lighting(
        &p.shading(),
        &at,
        tex,
        Vec3::from(colour),
        Vec3::Z,
        &[light()],
    )
}

fn over(src: Vec4, dst: Vec3) -> Vec3 {
    src.truncate() * src.w + (1.0 - src.w) * dst
}

#[test]
fn blended_faces_composite_in_draw_order_and_write_depth() {
    let a = 128.0 / 255.0;
    let back = (strip(0.0, true), 0);
    let front = (strip(0.1, true), 1);
    let hs = harness(&[back.clone(), front.clone()], 128);
    stage(&hs, "FrontFaces");
    let expect = over(lit(BLUE, 0.1, a), over(lit(RED, 0.0, a), grey()));
    let got = centre(&hs);
    assert!(
        (got.truncate() - expect).abs().max_element() < 2e-3,
        "{got} vs {expect}"
    );
    assert_eq!(got.w, 1.0, "the attachment's alpha is kept");
    // Front first: its depth hides the strip behind, which never blends.
    let hs = harness(&[front, back], 128);
    stage(&hs, "FrontFaces");
    let expect = over(lit(BLUE, 0.1, a), grey());
    let got = centre(&hs).truncate();
    assert!(
        (got - expect).abs().max_element() < 2e-3,
        "{got} vs {expect}"
    );
}

#[test]
fn the_prime_pass_lets_the_opaque_pass_shade_only_the_nearest_surface() {
    let hs = harness(&[(strip(0.1, true), 1), (strip(0.0, true), 0)], 255);
    stage(&hs, "PrimeDepth");
    assert_eq!(centre(&hs).truncate(), grey(), "no colour yet");
    stage(&hs, "Opaque");
    let expect = lit(BLUE, 0.1, 1.0).truncate();
    let got = centre(&hs).truncate();
    assert!(
        (got - expect).abs().max_element() < 2e-3,
        "{got} vs {expect}"
    );
    // Translucent texels fail the alpha test: nothing is primed or shaded.
    let hs = harness(&[(strip(0.1, true), 1)], 200);
    stage(&hs, "PrimeDepth");
    stage(&hs, "Opaque");
    assert_eq!(centre(&hs).truncate(), grey());
    assert!(
        hs.read("depth_buffer")
            .iter()
            .all(|&d| d == 1.0f32.to_bits())
    );
}

#[test]
fn back_and_front_stages_draw_opposite_faces() {
    for (facing, stage_name, drawn) in [
        (true, "BackFaces", false),
        (false, "BackFaces", true),
        (true, "FrontFaces", true),
        (false, "FrontFaces", false),
    ] {
        let hs = harness(&[(strip(0.0, facing), 0)], 128);
        stage(&hs, stage_name);
        let changed = centre(&hs).truncate() != grey();
        assert_eq!(changed, drawn, "facing the camera: {facing}, {stage_name}");
        // Only the front-face stage writes depth.
        let wrote = hs
            .read("depth_buffer")
            .iter()
            .any(|&d| d != 1.0f32.to_bits());
        assert_eq!(wrote, drawn && stage_name == "FrontFaces");
    }
}

#[test]
fn the_unprimed_opaque_stage_alpha_tests_and_writes_depth_itself() {
    let unprimed: ron::Value = ron::from_str("{\"primed\": false}").unwrap();
    for (alpha, drawn) in [(255u8, true), (200, false)] {
        let hs = harness(&[(strip(0.0, true), 0), (strip(0.1, true), 1)], alpha);
        run_with(&hs, &OPAQUE, &unprimed);
        let got = centre(&hs).truncate();
        let expect = if drawn {
            lit(BLUE, 0.1, 1.0).truncate()
        } else {
            grey()
        };
        assert!(
            (got - expect).abs().max_element() < 2e-3,
            "{alpha}: {got} vs {expect}"
        );
        let wrote = hs
            .read("depth_buffer")
            .iter()
            .any(|&d| d != 1.0f32.to_bits());
        assert_eq!(wrote, drawn);
    }
    // A disabled stage draws nothing.
    let hs = harness(&[(strip(0.0, true), 0)], 255);
    run_with(
        &hs,
        &PRIME_DEPTH,
        &ron::from_str("{\"enabled\": false}").unwrap(),
    );
    assert!(
        hs.read("depth_buffer")
            .iter()
            .all(|&d| d == 1.0f32.to_bits())
    );
}
