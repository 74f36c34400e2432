//! `report --crop`: one 1:1 pixel rectangle per view, cut from every
//! picture of that view when the pictures are copied into the report
//! (rows, references and FLIP maps alike), so thin strands and aliasing
//! keep their true size in a page small enough to commit.

use super::data::CropNote;
use miette::{Result, miette};
use std::str::FromStr;

/// `WxH` with an optional `+X+Y` (default: centred in the frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    pub w: u32,
    pub h: u32,
    pub at: Option<(u32, u32)>,
}

/// One `--crop`: `[VIEW=]WxH[+X+Y]`; without a view it is the default.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CropArg {
    pub view: Option<String>,
    pub rect: Rect,
    /// As given, for messages.
    pub text: String,
}

fn number(s: &str, what: &str) -> Result<u32, String> {
    s.parse()
        .map_err(|_| format!("{what} {s:?} is not a whole number of pixels"))
}

impl FromStr for Rect {
    type Err = String;
    fn from_str(s: &str) -> Result<Rect, String> {
        let (size, at) = match s.split_once('+') {
            Some((size, at)) => (size, Some(at)),
            None => (s, None),
        };
        let (w, h) = size
            .split_once('x')
            .ok_or_else(|| format!("{s:?} is not WxH or WxH+X+Y"))?;
        let (w, h) = (number(w, "width")?, number(h, "height")?);
        if w == 0 || h == 0 {
            return Err(format!("{s:?}: the rectangle is empty"));
        }
        let at = match at.map(|a| a.split_once('+')) {
            None => None,
            Some(Some((x, y))) => Some((number(x, "X")?, number(y, "Y")?)),
            Some(None) => return Err(format!("{s:?}: the offset is +X+Y")),
        };
        Ok(Rect { w, h, at })
    }
}

impl FromStr for CropArg {
    type Err = String;
    fn from_str(s: &str) -> Result<CropArg, String> {
        let (view, rect) = match s.split_once('=') {
            Some(("", _)) => return Err(format!("{s:?}: no view before `=`")),
            Some((v, r)) => (Some(v.to_string()), r),
            None => (None, s),
        };
        Ok(CropArg {
            view,
            rect: rect.parse()?,
            text: s.to_string(),
        })
    }
}

/// Every `--crop`, checked: one default at most, one per view at most.
#[derive(Debug, Default)]
pub struct Crops {
    args: Vec<CropArg>,
}

impl Crops {
    pub fn new(args: &[CropArg]) -> Result<Crops> {
        for (i, a) in args.iter().enumerate() {
            if let Some(b) = args[..i].iter().find(|b| b.view == a.view) {
                let whose = a
                    .view
                    .as_deref()
                    .map_or("every view".to_string(), |v| format!("view {v:?}"));
                return Err(miette!(
                    "--crop {} and --crop {} both crop {whose}",
                    b.text,
                    a.text
                ));
            }
        }
        Ok(Crops {
            args: args.to_vec(),
        })
    }

    pub fn is_empty(&self) -> bool {
        self.args.is_empty()
    }

    /// Every `--crop VIEW=` names one of `views`.
    pub fn check_views(&self, views: &[&str], json: &str) -> Result<()> {
        for a in &self.args {
            if let Some(v) = &a.view
                && !views.contains(&v.as_str())
            {
                return Err(miette!(
                    help = format!("its views: {}", views.join(", ")),
                    "--crop {}: {json} has no view {v:?}",
                    a.text
                ));
            }
        }
        Ok(())
    }

    /// The crop of `view`: its own, else the default.
    pub fn get(&self, view: &str) -> Option<&CropArg> {
        let own = self.args.iter().find(|a| a.view.as_deref() == Some(view));
        own.or_else(|| self.args.iter().find(|a| a.view.is_none()))
    }
}

/// Where `arg` lies in a `w`x`h` picture (`name`, for the message).
pub fn place(arg: &CropArg, name: &str, (w, h): (u32, u32)) -> Result<(u32, u32)> {
    let r = arg.rect;
    let (x, y) =
        r.at.unwrap_or((w.saturating_sub(r.w) / 2, h.saturating_sub(r.h) / 2));
    let fits = u64::from(x) + u64::from(r.w) <= u64::from(w)
        && u64::from(y) + u64::from(r.h) <= u64::from(h);
    if !fits {
        return Err(miette!(
            help = "a crop must lie inside the pictures: give a smaller WxH or another +X+Y",
            "--crop {}: {name} is {w}x{h}; {}x{} at ({x}, {y}) does not fit inside it",
            arg.text,
            r.w,
            r.h
        ));
    }
    Ok((x, y))
}

/// The record of `r` cut at `at` from `view`'s pictures of `size`, which
/// were `earlier`'s crop of the frame already, if any.
pub fn note(
    view: &str,
    at: (u32, u32),
    r: Rect,
    size: (u32, u32),
    earlier: Option<&CropNote>,
) -> CropNote {
    let (dx, dy, frame) = earlier.map_or((0, 0, size), |e| {
        (e.x, e.y, (e.frame_width, e.frame_height))
    });
    CropNote {
        view: view.to_string(),
        x: dx + at.0,
        y: dy + at.1,
        width: r.w,
        height: r.h,
        frame_width: frame.0,
        frame_height: frame.1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arg(s: &str) -> CropArg {
        s.parse().unwrap()
    }

    #[test]
    fn parses_size_offset_and_view() {
        let a = arg("64x48");
        assert_eq!(
            (a.view, a.rect),
            (
                None,
                Rect {
                    w: 64,
                    h: 48,
                    at: None
                }
            )
        );
        let a = arg("far=640x360+10+20");
        assert_eq!(a.view.as_deref(), Some("far"));
        assert_eq!(a.rect.at, Some((10, 20)));
        for bad in ["64", "64x", "0x4", "64x48+3", "=64x48", "ax4", "4x4+1+y"] {
            assert!(bad.parse::<CropArg>().is_err(), "{bad}");
        }
    }

    #[test]
    fn a_view_takes_its_own_crop_else_the_default() {
        let c = Crops::new(&[arg("close=8x8"), arg("4x4")]).unwrap();
        assert_eq!(c.get("close").unwrap().rect.w, 8);
        assert_eq!(c.get("far").unwrap().rect.w, 4);
        assert!(Crops::new(&[arg("4x4"), arg("8x8")]).is_err());
        assert!(Crops::new(&[arg("far=4x4"), arg("far=8x8")]).is_err());
        assert!(c.check_views(&["close", "far"], "b.json").is_ok());
        assert!(c.check_views(&["far"], "b.json").is_err());
    }

    #[test]
    fn centred_unless_placed_and_always_inside() {
        assert_eq!(place(&arg("64x48"), "a", (160, 90)).unwrap(), (48, 21));
        assert_eq!(
            place(&arg("64x48+96+42"), "a", (160, 90)).unwrap(),
            (96, 42)
        );
        let e = place(&arg("64x48+97+0"), "pictures/a.png", (160, 90)).unwrap_err();
        assert!(format!("{e}").contains("pictures/a.png is 160x90"), "{e}");
        assert!(place(&arg("200x10"), "a", (160, 90)).is_err());
    }
}
