//! Times asset work: procedural generation at the Lipp evaluation size (130k strands x 32
//! points), hair-mesh fitting, and loading every real file in ../shared/grooms.
//!
//!     cargo run --release -p strandgraph-assets --example timings

use std::path::PathBuf;
use std::time::Instant;

use strandgraph_assets::hairmesh::HairMeshParams;
use strandgraph_assets::procedural::surface::{Shape, Surface};
use strandgraph_assets::procedural::{GroomParams, HeadParams, Style};
use strandgraph_assets::{HairMesh, LoadOptions, Units, load_groom, load_mesh};

fn time<T>(what: &str, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let r = f();
    println!("{what}: {:.1} ms", t.elapsed().as_secs_f64() * 1e3);
    r
}

fn main() {
    println!("threads: {}", rayon::current_num_threads());
    let head = time("head mesh (128 segments)", || {
        Surface::procedural(Shape::Head(HeadParams::default()))
    });
    let g = time("generate Long groom 130,000 x 32", || {
        GroomParams {
            style: Style::Long,
            strands: 130_000,
            points: 32,
            ..Default::default()
        }
        .generate(&head)
    });
    let params = HairMeshParams {
        bundles: 1024,
        layers: 8,
        style: Default::default(),
        seed: 1,
    };
    time("fit hair mesh 1,024 bundles x 8 layers to it", || {
        HairMesh::fit(&g.groom, &params)
    });
    let guide = GroomParams {
        style: Style::Long,
        ..Default::default()
    };
    let m = time("procedural hair mesh 1,024 x 8", || {
        HairMesh::procedural(&head, &guide, &params, 130_000)
    });
    time("strands from hair mesh 130,000 x 32", || {
        m.to_groom(32, 7e-5)
    });
    time("shuffle 130,000 strands", || g.groom.shuffled(1));

    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/grooms"));
    for (f, units) in [
        ("sintel/sintel_hair_16pts.tfx", Units::Metres),
        ("tressfx/ratboy_mohawk.v4.tfx", Units::Metres),
        ("tressfx/bear.v3.tfx", Units::Centimetres),
        ("tressfx/testhair1.v3.tfx", Units::Centimetres),
        ("tressfx/ponytail_side.v3.tfx", Units::Centimetres),
        ("tressfx/ruby_long_hair.v2.tfx", Units::Centimetres),
        ("tressfx/hair_free.v2.tfx", Units::Centimetres),
    ] {
        let opts = LoadOptions {
            units,
            ..Default::default()
        };
        if let Err(e) = time(&format!("load {f}"), || load_groom(&dir.join(f), &opts)) {
            println!("  error: {e}");
        }
    }
    if let Err(e) = time("load sintel/sintel_head.obj", || {
        load_mesh(&dir.join("sintel/sintel_head.obj"), Units::Metres)
    }) {
        println!("  error: {e}");
    }
}
