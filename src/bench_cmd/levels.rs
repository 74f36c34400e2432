//! `bench --levels`: each ash cell's frame timed level by level
//! ([`Session::run_levels_timed`]), the medians written into bench.json as
//! the cell's `levels`. Per-pass queries make a queue's passes wait for
//! each other and the frame timed at its bounds says nothing of where its
//! time goes; the levels show which queue's chain of levels the frame
//! waits for, with the passes overlapping as they do untimed.

use super::Args;
use super::report::median;
use miette::Result;
use serde_json::{Value, json};
use strandgraph_passes::backend::{LevelTime, Session};
use strandgraph_passes::upload::Upload;

/// One level's median begin and end over the frames, ms from each frame's
/// first batch start.
#[derive(Debug, Clone)]
pub struct LevelSpread {
    pub queue: usize,
    pub batch: usize,
    pub passes: Vec<String>,
    pub begin: f64,
    pub end: f64,
}

impl LevelSpread {
    pub fn json(&self) -> Value {
        json!({
            "queue": self.queue,
            "batch": self.batch,
            "passes": self.passes,
            "begin_ms": self.begin,
            "end_ms": self.end,
        })
    }
}

/// `args.frames` frames timed level by level, after the cell's other
/// frames (`first` is the next frame's index into `inputs`); empty where
/// the backend cannot.
pub fn level_frames(
    session: &mut dyn Session,
    inputs: &[Upload],
    first: usize,
    args: &Args,
) -> Result<Vec<LevelSpread>> {
    let input = |k: usize| &inputs[k.min(inputs.len() - 1)];
    let mut frames: Vec<Vec<LevelTime>> = Vec::with_capacity(args.frames);
    for k in first..first + args.frames {
        match session.run_levels_timed(input(k))? {
            Some(levels) => frames.push(levels),
            None => return Ok(Vec::new()),
        }
    }
    Ok(medians(&frames))
}

/// Per level (every frame records the same levels), the median begin and end.
fn medians(frames: &[Vec<LevelTime>]) -> Vec<LevelSpread> {
    let Some(shape) = frames.first() else {
        return Vec::new();
    };
    shape
        .iter()
        .enumerate()
        .map(|(i, level)| {
            let at = |f: fn(&LevelTime) -> f64| -> f64 {
                median(&frames.iter().map(|fr| f(&fr[i])).collect::<Vec<_>>())
            };
            LevelSpread {
                queue: level.queue,
                batch: level.batch,
                passes: level.passes.clone(),
                begin: at(|l| l.span.0),
                end: at(|l| l.span.1),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(name: &str, span: (f64, f64)) -> LevelTime {
        LevelTime {
            queue: 0,
            batch: 0,
            passes: vec![name.into()],
            span,
        }
    }

    #[test]
    fn each_level_takes_the_median_of_its_own_spans() {
        let frames = vec![
            vec![level("a", (0.0, 1.0)), level("b", (1.0, 3.0))],
            vec![level("a", (0.0, 2.0)), level("b", (2.0, 5.0))],
            vec![level("a", (0.0, 1.5)), level("b", (1.5, 4.0))],
        ];
        let m = medians(&frames);
        assert_eq!(m.len(), 2);
        assert_eq!(
            (m[0].passes[0].as_str(), m[0].begin, m[0].end),
            ("a", 0.0, 1.5)
        );
        assert_eq!(
            (m[1].passes[0].as_str(), m[1].begin, m[1].end),
            ("b", 1.5, 4.0)
        );
    }
}
