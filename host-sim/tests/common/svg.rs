//! Reading back what an SVG plot draws: its axes (from the tick labels' positions and
//! values), its polylines and circles by colour, mapped back to data coordinates. Lets a
//! test check that a plot draws the data it should, not only that the file exists.

use std::path::Path;

/// One `<text>` element.
#[derive(Clone, Debug)]
struct Text {
    x: f64,
    y: f64,
    anchor: String,
    rotated: bool,
    content: String,
}

/// A linear map from pixels to data: value = offset + scale * pixel.
#[derive(Clone, Copy, Debug)]
pub struct Axis {
    offset: f64,
    scale: f64,
}

impl Axis {
    /// Least squares through (pixel, value) pairs (at least two distinct pixels).
    fn fit(ticks: &[(f64, f64)]) -> Axis {
        assert!(ticks.len() >= 2, "an axis needs two tick labels: {ticks:?}");
        let n = ticks.len() as f64;
        let (sp, sv) = ticks.iter().fold((0.0, 0.0), |a, t| (a.0 + t.0, a.1 + t.1));
        let (mp, mv) = (sp / n, sv / n);
        let (mut cov, mut var) = (0.0, 0.0);
        for (p, v) in ticks {
            cov += (p - mp) * (v - mv);
            var += (p - mp) * (p - mp);
        }
        let scale = cov / var;
        let axis = Axis {
            offset: mv - scale * mp,
            scale,
        };
        // every tick label sits on the line to its rounding (labels keep 4 digits, pixels
        // are whole)
        for &(p, v) in ticks {
            let off = (axis.value(p) - v).abs() / scale.abs();
            assert!(
                off < 1.0,
                "tick {v} at pixel {p} is {off} px off the axis {axis:?}"
            );
        }
        axis
    }

    /// The data value at `pixel`.
    pub fn value(&self, pixel: f64) -> f64 {
        self.offset + self.scale * pixel
    }

    /// The pixel of data value `v`.
    pub fn pixel(&self, v: f64) -> f64 {
        (v - self.offset) / self.scale
    }

    /// Data units per pixel.
    pub fn per_pixel(&self) -> f64 {
        self.scale.abs()
    }
}

/// A plot's SVG, read back.
pub struct Svg {
    text: String,
    /// x axis (pixels to data).
    pub x: Axis,
    /// y axis (pixels to data).
    pub y: Axis,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    let end = tag[start..].find('"')? + start;
    Some(tag[start..end].to_string())
}

fn num_attr(tag: &str, name: &str) -> f64 {
    attr(tag, name)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no number {name} in {tag}"))
}

/// Every element `<name ...>` (its opening tag) and, for `<text>`, its content.
fn elements<'a>(svg: &'a str, name: &str) -> Vec<(&'a str, &'a str)> {
    let open = format!("<{name} ");
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find(&open) {
        let from = &rest[i..];
        let end = from.find('>').expect("a closed tag") + 1;
        let (tag, after) = from.split_at(end);
        let content = after.split('<').next().unwrap_or("");
        out.push((tag, content));
        rest = after;
    }
    out
}

impl Svg {
    /// Read `path` and fit its axes to the tick labels.
    pub fn read(path: &Path) -> Svg {
        let text = std::fs::read_to_string(path)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
        let texts: Vec<Text> = elements(&text, "text")
            .into_iter()
            .map(|(tag, content)| Text {
                x: num_attr(tag, "x"),
                y: num_attr(tag, "y"),
                anchor: attr(tag, "text-anchor").unwrap_or_default(),
                rotated: tag.contains("transform="),
                content: content.trim().to_string(),
            })
            .collect();
        let ticks = |anchor: &str, along_x: bool| -> Vec<(f64, f64)> {
            texts
                .iter()
                .filter(|t| t.anchor == anchor && !t.rotated)
                .filter_map(|t| {
                    let v: f64 = t.content.parse().ok()?;
                    Some((if along_x { t.x } else { t.y }, v))
                })
                .collect()
        };
        // x tick labels are centred under their tick; the title and the axis description
        // are centred too but are not numbers
        let x = Axis::fit(&ticks("middle", true));
        let y = Axis::fit(&ticks("end", false));
        Svg { text, x, y }
    }

    /// The polylines stroked in `colour` (`#RRGGBB`), each as pixel points.
    pub fn polylines(&self, colour: &str) -> Vec<Vec<(f64, f64)>> {
        elements(&self.text, "polyline")
            .into_iter()
            .filter(|(tag, _)| attr(tag, "stroke").as_deref() == Some(colour))
            .map(|(tag, _)| {
                attr(tag, "points")
                    .unwrap_or_default()
                    .split_whitespace()
                    .map(|p| {
                        let (a, b) = p.split_once(',').expect("x,y");
                        (a.parse().unwrap(), b.parse().unwrap())
                    })
                    .collect()
            })
            .collect()
    }

    /// The polyline in `colour` with the most points (of two-point lines, the longest), in
    /// data coordinates: a series' line, not its legend sample (two points, 24 px).
    pub fn line(&self, colour: &str) -> Vec<(f64, f64)> {
        let length = |l: &Vec<(f64, f64)>| {
            l.windows(2)
                .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
                .sum::<f64>()
        };
        let longest = self
            .polylines(colour)
            .into_iter()
            .max_by(|a, b| a.len().cmp(&b.len()).then(length(a).total_cmp(&length(b))))
            .unwrap_or_else(|| panic!("no polyline in {colour}"));
        longest.iter().map(|&p| self.data(p)).collect()
    }

    /// The centres of the circles filled in `colour`, in pixels.
    pub fn circles(&self, colour: &str) -> Vec<(f64, f64)> {
        elements(&self.text, "circle")
            .into_iter()
            .filter(|(tag, _)| attr(tag, "fill").as_deref() == Some(colour))
            .map(|(tag, _)| (num_attr(tag, "cx"), num_attr(tag, "cy")))
            .collect()
    }

    /// A pixel point in data coordinates.
    pub fn data(&self, (px, py): (f64, f64)) -> (f64, f64) {
        (self.x.value(px), self.y.value(py))
    }

    /// A data point in pixels.
    pub fn pixel(&self, (x, y): (f64, f64)) -> (f64, f64) {
        (self.x.pixel(x), self.y.pixel(y))
    }

    /// Check that the dots of `colour` are exactly the `want` data points (and one legend
    /// sample): every wanted point has a dot within `tol_px` pixels and every dot but one
    /// is within `tol_px` of a wanted point.
    pub fn assert_dots(&self, colour: &str, want: &[(f64, f64)], tol_px: f64) {
        let dots = self.circles(colour);
        let want_px: Vec<(f64, f64)> = want.iter().map(|&p| self.pixel(p)).collect();
        let near = |a: (f64, f64), set: &[(f64, f64)]| {
            set.iter()
                .map(|b| (a.0 - b.0).hypot(a.1 - b.1))
                .fold(f64::INFINITY, f64::min)
        };
        for (w, p) in want.iter().zip(&want_px) {
            let d = near(*p, &dots);
            assert!(
                d <= tol_px,
                "{colour}: no dot within {tol_px} px of {w:?} (nearest {d} px)"
            );
        }
        let strays = dots.iter().filter(|d| near(**d, &want_px) > tol_px).count();
        assert!(
            strays <= 1,
            "{colour}: {strays} dots match no data point ({} dots, {} points)",
            dots.len(),
            want.len()
        );
    }
}
