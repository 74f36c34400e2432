//! The time-versus-FLIP chart's point labels: each beside its point,
//! moved past points and labels already placed, with a leader line where
//! it had to move.

use super::{AXIS, Area, drawn, font, text_width};
use miette::Result;
use plotters::element::PathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

const SIZE: u32 = 12;

/// A label's or a point's box: left, top, right, bottom.
pub(super) type Rect = (i32, i32, i32, i32);

/// How much `r` overlaps the boxes already `taken`, in square pixels.
fn overlap(r: Rect, taken: &[Rect]) -> i32 {
    taken
        .iter()
        .map(|q| {
            let w = (r.2.min(q.2) - r.0.max(q.0)).max(0);
            let h = (r.3.min(q.3) - r.1.max(q.1)).max(0);
            w * h
        })
        .sum()
}

/// Where each label goes: beside its point, right or left, moved up or
/// down past points and labels already placed (rows of nearly equal time
/// and FLIP would print over each other); where every spot is taken, the
/// one it overlaps least. Labels stay inside `bounds` (off the axes' tick
/// labels). `(x, y, moved)`: the label's left end and middle, and whether
/// it left its point's side.
pub(super) fn place_labels(
    widths: &[i32],
    at: &[(i32, i32)],
    bounds: Rect,
) -> Vec<(i32, i32, bool)> {
    let (left, top, right, bottom) = bounds;
    let mut taken: Vec<Rect> = at
        .iter()
        .map(|&(x, y)| (x - 6, y - 6, x + 6, y + 6))
        .collect();
    let mut out = Vec::with_capacity(at.len());
    for (&tw, &(px, py)) in widths.iter().zip(at) {
        // Right, left, then centred over or under the point (off 0 only).
        let sides = [px + 10, px - 10 - tw, px - tw / 2];
        let offsets = (0..=7).flat_map(|k| {
            if k == 0 {
                vec![0]
            } else {
                vec![-16 * k, 16 * k]
            }
        });
        let rect = |x: i32, y: i32| (x, y - 8, x + tw, y + 8);
        let spot = offsets
            .flat_map(|dy| sides.map(|x| (x, py - 8 + dy, dy != 0)))
            .filter(|&(x, _, moved)| moved || x != px - tw / 2)
            .filter(|&(x, y, _)| x >= left && x + tw <= right && y - 8 >= top && y + 8 <= bottom)
            .min_by_key(|&(x, y, _)| overlap(rect(x, y), &taken))
            .unwrap_or((sides[0], py - 8, false));
        taken.push(rect(spot.0, spot.1));
        out.push(spot);
    }
    out
}

/// Each text beside its point `at` (pixels of `area`) inside `bounds`,
/// with a leader line where it had to move.
pub(super) fn draw_labels(
    area: &Area<'_>,
    texts: &[&str],
    at: &[(i32, i32)],
    bounds: Rect,
) -> Result<()> {
    let what = "time-versus-FLIP";
    let widths: Vec<i32> = texts.iter().map(|t| text_width(t, SIZE)).collect();
    let spots = place_labels(&widths, at, bounds);
    for ((text, &(px, py)), ((x, y, moved), tw)) in
        texts.iter().zip(at).zip(spots.into_iter().zip(widths))
    {
        if moved {
            // To the label's near end, or its near edge when centred.
            let end = match (x > px, x + tw < px) {
                (true, _) => (x - 2, y),
                (_, true) => (x + tw + 2, y),
                _ if y < py => (px, y + 7),
                _ => (px, y - 7),
            };
            let line = PathElement::new(vec![(px, py), end], AXIS.mix(0.6));
            drawn(what, area.draw(&line))?;
        }
        let style = font(SIZE).pos(Pos::new(HPos::Left, VPos::Center));
        drawn(what, area.draw(&Text::new(text.to_string(), (x, y), style)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_of_coincident_points_do_not_overlap() {
        let at = [(100, 100), (102, 100), (104, 101), (600, 50)];
        let spots = place_labels(&[80, 80, 80, 80], &at, (0, 0, 640, 400));
        for (i, a) in spots.iter().enumerate() {
            for b in &spots[i + 1..] {
                let apart = (a.0 - b.0).abs() >= 80 || (a.1 - b.1).abs() >= 16;
                assert!(apart, "{a:?} and {b:?} overlap");
            }
        }
        // The last point is near the right edge: its label goes left.
        assert!(spots[3].0 + 80 <= 600, "{:?}", spots[3]);
        assert!(!spots[0].2, "the first label stays beside its point");
        // Nor over the axes: a point by the left bound keeps its label right.
        let spots = place_labels(&[80], &[(60, 200)], (50, 0, 640, 400));
        assert!(spots[0].0 >= 50, "{spots:?}");
    }
}
