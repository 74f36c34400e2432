//! Fill-rule checks shared by the tests of both triangle rasterizers: the
//! hardware rules the graphics roofline's CPU kernel follows
//! (`hardware_raster`) and the compute rasterizer of the opaque head
//! (`opaque_mesh::setup`). Each takes the rasterizer as `cover`: the pixel
//! centres a screen-space triangle (pixels, y down, either winding) covers
//! on a `w` × `h` screen.

/// A rasterizer under test.
pub type Cover<'a> = &'a dyn Fn([[f32; 2]; 3], u32, u32) -> Vec<(u32, u32)>;

fn area_and_perimeter(t: [[f32; 2]; 3]) -> (f32, f32) {
    let d = |a: [f32; 2], b: [f32; 2]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
    let cross =
        (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[1][1] - t[0][1]) * (t[2][0] - t[0][0]);
    (
        cross.abs() * 0.5,
        d(t[0], t[1]) + d(t[1], t[2]) + d(t[2], t[0]),
    )
}

/// Covered pixel counts match the analytic area within the perimeter's band.
pub fn covered_pixels_match_the_analytic_area(cover: Cover<'_>) {
    // A small deterministic generator: no dependency for a few numbers.
    let mut seed = 0x2545_f491_u32;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        (seed >> 8) as f32 / (1 << 24) as f32
    };
    for _ in 0..200 {
        let tri = [0; 3].map(|_| [next() * 60.0 + 2.0, next() * 60.0 + 2.0]);
        let (area, perimeter) = area_and_perimeter(tri);
        let n = cover(tri, 64, 64).len() as f32;
        // Pixels whose centre is covered differ from the area by at most
        // the band of pixels the perimeter passes through.
        assert!(
            (n - area).abs() <= perimeter + 1.0,
            "{tri:?}: {n} pixels, area {area}"
        );
    }
    // An axis-aligned right triangle through pixel centres: exact count.
    // Legs along x = 0.5 (left edge, kept) and y = 0.5 (top edge, kept);
    // the hypotenuse is a right edge, so centres on it are dropped.
    let n = cover([[0.5, 0.5], [10.5, 0.5], [0.5, 10.5]], 16, 16).len();
    assert_eq!(n, (1..=10).sum::<usize>());
}

/// Triangles sharing edges cover every pixel of their union exactly once.
pub fn shared_edges_cover_every_pixel_once(cover: Cover<'_>) {
    let (w, h) = (24u32, 24u32);
    // A fan of 8 triangles around a pixel centre, rim corners on pixel
    // centres: every shared edge passes through pixel centres, and so does
    // the hub, the worst case for the fill rule.
    let hub = [12.5f32, 12.5];
    let rim: [[f32; 2]; 8] = [
        [2.5, 2.5],
        [12.5, 0.5],
        [22.5, 2.5],
        [23.5, 12.5],
        [22.5, 22.5],
        [12.5, 23.5],
        [2.5, 22.5],
        [0.5, 12.5],
    ];
    let mut count = vec![0u32; (w * h) as usize];
    for k in 0..8 {
        for (x, y) in cover([hub, rim[k], rim[(k + 1) % 8]], w, h) {
            count[(y * w + x) as usize] += 1;
        }
    }
    // Every centre strictly inside the convex octagon is covered once,
    // nothing is covered twice.
    let inside = |p: [f32; 2]| {
        (0..8).all(|k| {
            let (a, b) = (rim[k], rim[(k + 1) % 8]);
            // Clockwise on screen (y down) means the interior is to the right.
            (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0.0
        })
    };
    for y in 0..h {
        for x in 0..w {
            let c = count[(y * w + x) as usize];
            assert!(c <= 1, "pixel ({x}, {y}) covered {c} times");
            if inside([x as f32 + 0.5, y as f32 + 0.5]) {
                assert_eq!(c, 1, "pixel ({x}, {y}) missed");
            }
        }
    }
    // Two triangles of a rectangle: the union is exactly the pixels
    // whose centres lie in [0.5, 20.5) × [0.5, 10.5) (top and left kept).
    let q = [[0.5f32, 0.5], [20.5, 0.5], [20.5, 10.5], [0.5, 10.5]];
    let mut count = vec![0u32; (w * h) as usize];
    for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
        for (x, y) in cover(t, w, h) {
            count[(y * w + x) as usize] += 1;
        }
    }
    for y in 0..h {
        for x in 0..w {
            let expected = u32::from(x < 20 && y < 10);
            assert_eq!(count[(y * w + x) as usize], expected, "({x}, {y})");
        }
    }
}
