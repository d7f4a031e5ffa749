//! Scatter plots of a trade-off (e.g. error against frame time) with the Pareto front marked,
//! written as PNG; the Pareto front itself.
//!
//! Drawn with plotters into an RGB buffer and encoded by `image` (the PNG is written with
//! [`atomic_write`] like every other output). Text needs a TrueType font read at run time
//! ([`register_font`]): without one the plot is still drawn, without any text.

use std::{
    ops::Range,
    path::{Path, PathBuf},
    sync::OnceLock,
};

use anyhow::{Context, Result, anyhow};
use plotters::{
    coord::{Shift, ranged1d::ValueFormatter},
    prelude::*,
};

use hyrt::output::atomic_write;

/// Which points are on the Pareto front of `points` = `(time, quality)`: lower time and higher
/// quality are better, and a point is on the front when no other point is at least as good in
/// both and strictly better in one. So equal points are all on the front, a quality of `+inf`
/// (e.g. the PSNR of an identical image) is the best quality, and a point with a NaN quality
/// or a non-finite time is never on the front (nor keeps another point off it).
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    let valid = |&(t, q): &(f64, f64)| t.is_finite() && !q.is_nan();
    let dominates = |a: &(f64, f64), b: &(f64, f64)| a.0 <= b.0 && a.1 >= b.1 && (a.0 < b.0 || a.1 > b.1);
    points.iter().map(|p| valid(p) && !points.iter().any(|o| valid(o) && dominates(o, p))).collect()
}

/// One point of a [`Plot`].
#[derive(Clone, Debug)]
pub struct Point {
    pub x: f64,
    /// `+inf` is drawn on a line of its own above the finite values, `-inf` at the bottom;
    /// NaN is not drawn.
    pub y: f64,
    /// Drawn beside the point when non-empty.
    pub label: String,
    /// On the Pareto front: highlighted and joined by the front's staircase.
    pub front: bool,
}

/// A scatter plot.
#[derive(Clone, Debug)]
pub struct Plot<'a> {
    pub title: &'a str,
    pub x_name: &'a str,
    pub y_name: &'a str,
    pub points: &'a [Point],
    /// A vertical dashed line at this x with its name (e.g. the reference's frame time).
    pub x_marker: Option<(f64, &'a str)>,
    /// Image size in pixels.
    pub size: (u32, u32),
}

/// The font family name under which [`register_font`] registers the font.
const FAMILY: &str = "sans-serif";

/// Where a font is looked for: `$HYRT_FONT` if set, then DejaVu Sans where Debian puts it.
pub fn font_candidates() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> =
        std::env::var_os("HYRT_FONT").filter(|s| !s.is_empty()).map(PathBuf::from).into_iter().collect();
    v.push(PathBuf::from("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"));
    v
}

/// Registers the first usable font of [`font_candidates`] for the plots' text, once per
/// process. `Err` lists each path tried and why it failed.
pub fn register_font() -> std::result::Result<PathBuf, String> {
    static FONT: OnceLock<std::result::Result<PathBuf, String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let mut tried = Vec::new();
        for p in font_candidates() {
            match std::fs::read(&p) {
                Ok(bytes) => {
                    // plotters keeps fonts for the whole process, as `&'static [u8]`; this runs
                    // once, so leaking the one file is the simplest correct owner.
                    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                    match plotters::style::register_font(FAMILY, FontStyle::Normal, bytes) {
                        Ok(()) => return Ok(p),
                        Err(_) => tried.push(format!("{} (not a TrueType font)", p.display())),
                    }
                }
                Err(e) => tried.push(format!("{} ({e})", p.display())),
            }
        }
        Err(tried.join(", "))
    })
    .clone()
}

/// Draws `plot` and writes it as a PNG to `path`. With `text` false (no font registered) only
/// the axes' frame, grid, points and lines are drawn.
pub fn write_png(path: &Path, plot: &Plot, text: bool) -> Result<()> {
    let (w, h) = plot.size;
    let mut buf = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let axes = axes(plot);
        if axes.log_x {
            draw(&root, axes.x.clone().log_scale(), &axes, plot, text)?;
        } else {
            draw(&root, axes.x.clone(), &axes, plot, text)?;
        }
        root.present().map_err(|e| anyhow!("cannot draw the plot: {e}"))?;
    }
    atomic_write(path, |tmp| {
        image::save_buffer_with_format(tmp, &buf, w, h, image::ColorType::Rgb8, image::ImageFormat::Png)
            .map_err(Into::into)
    })
    .with_context(|| format!("{}: cannot write the plot", path.display()))
}

/// The axes of a plot.
struct Axes {
    x: Range<f64>,
    /// Logarithmic x: positive values spanning more than 10x.
    log_x: bool,
    y: Range<f64>,
    /// Where `+inf` values are drawn (in a band above the finite ones), if there are any.
    inf_y: Option<f64>,
}

/// The axes' ranges, with a margin; infinite values are left out of the y range.
fn axes(plot: &Plot) -> Axes {
    let xs = plot.points.iter().map(|p| p.x).chain(plot.x_marker.map(|m| m.0)).filter(|x| x.is_finite());
    let (x0, x1) = min_max(xs).unwrap_or((0.0, 1.0));
    let (y0, y1) = min_max(plot.points.iter().map(|p| p.y).filter(|y| y.is_finite())).unwrap_or((0.0, 1.0));
    let log_x = x0 > 0.0 && x1 / x0 > 10.0;
    let x = if log_x { x0 / 1.15..x1 * 1.15 } else { pad(x0, x1) };
    let y = pad(y0, y1);
    if plot.points.iter().any(|p| p.y == f64::INFINITY && p.x.is_finite()) {
        let band = 0.1 * (y.end - y.start);
        Axes { x, log_x, y: y.start..y.end + 2.0 * band, inf_y: Some(y.end + band) }
    } else {
        Axes { x, log_x, y, inf_y: None }
    }
}

fn min_max(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    v.fold(None, |acc, x| match acc {
        None => Some((x, x)),
        Some((lo, hi)) => Some((lo.min(x), hi.max(x))),
    })
}

/// `lo..hi` widened by 8 % on each side (by 5 % of the value, or 1, when `lo == hi`).
fn pad(lo: f64, hi: f64) -> Range<f64> {
    let m = if hi > lo { 0.08 * (hi - lo) } else { (0.05 * lo.abs()).max(1.0) };
    lo - m..hi + m
}

const GREY: RGBColor = RGBColor(150, 150, 150);
const POINT: RGBColor = RGBColor(70, 110, 190);
const FRONT: RGBColor = RGBColor(210, 50, 40);

fn draw<X>(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    x_range: X,
    axes: &Axes,
    plot: &Plot,
    text: bool,
) -> Result<()>
where
    X: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
{
    let err = |e: &dyn std::fmt::Display| anyhow!("cannot draw the plot: {e}");
    let (log_x, x_end, y_range, inf_y) = (axes.log_x, axes.x.end, axes.y.clone(), axes.inf_y);
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let font = |size: f64| (FAMILY, size).into_font();
    let mut builder = ChartBuilder::on(root);
    builder.margin(16);
    if text {
        builder.caption(plot.title, font(20.0)).x_label_area_size(48).y_label_area_size(64);
    }
    let mut chart = builder.build_cartesian_2d(x_range, y_range.clone()).map_err(|e| err(&e))?;
    // No ticks in the band of the infinite values: they would read as finite.
    let finite_top = inf_y.map_or(f64::INFINITY, |t| 2.0 * t - y_range.end);
    let y_label = move |y: &f64| {
        if *y > finite_top + 1e-9 {
            String::new()
        } else {
            <plotters::coord::types::RangedCoordf64 as ValueFormatter<f64>>::format(y)
        }
    };
    // On a log axis only 1, 2 and 5 times a power of ten: the others would crowd each decade's
    // right end.
    let x_label = move |x: &f64| {
        let m = x / 10f64.powf(x.log10().floor());
        let nice = [1.0, 2.0, 5.0, 10.0].iter().any(|n| (m - n).abs() < 1e-6 * n);
        if !log_x || nice {
            <plotters::coord::types::RangedCoordf64 as ValueFormatter<f64>>::format(x)
        } else {
            String::new()
        }
    };
    let mut mesh = chart.configure_mesh();
    mesh.light_line_style(RGBColor(235, 235, 235)).bold_line_style(RGBColor(205, 205, 205));
    if text {
        mesh.x_desc(plot.x_name).y_desc(plot.y_name).label_style(font(15.0)).axis_desc_style(font(16.0));
        mesh.y_label_formatter(&y_label).x_label_formatter(&x_label);
        if log_x {
            // Ask for every 1..9 times a power of ten; the formatter keeps 1, 2 and 5.
            mesh.x_labels(40);
        }
    }
    // Without text there are no label areas, so the grid is drawn but no tick labels.
    mesh.draw().map_err(|e| err(&e))?;

    let area = chart.plotting_area().get_pixel_range();
    let bounds: Rect = (area.0.start, area.1.start, area.0.end, area.1.end);
    if !text {
        // The axes live in the label areas: frame the plot instead.
        let frame = [(bounds.0, bounds.1), (bounds.2 - 1, bounds.3 - 1)];
        root.draw(&Rectangle::new(frame, BLACK.stroke_width(1))).map_err(|e| err(&e))?;
    }
    // +inf (e.g. an image identical to the reference) sits on its own line above the others.
    let y_of = |y: f64| match (y, inf_y) {
        (f64::INFINITY, Some(top)) => top,
        (f64::NEG_INFINITY, _) => y_range.start,
        _ => y,
    };
    let drawable: Vec<&Point> = plot.points.iter().filter(|p| p.x.is_finite() && !p.y.is_nan()).collect();
    let at = |p: &Point| chart.backend_coord(&(p.x, y_of(p.y)));
    let mut labels: Vec<Label> = Vec::new();
    // Lines drawn so far, as thin rectangles that labels keep off.
    let mut lines: Vec<Rect> = Vec::new();
    let segment = |a: (i32, i32), b: (i32, i32)| {
        (a.0.min(b.0) - 1, a.1.min(b.1) - 1, a.0.max(b.0) + 1, a.1.max(b.1) + 1)
    };

    if let Some(top) = inf_y {
        let y = chart.backend_coord(&(x_end, top)).1;
        dashed(root, (bounds.0, y), (bounds.2, y), GREY.mix(0.7))?;
        lines.push(segment((bounds.0, y), (bounds.2, y)));
        if text {
            // A tick label of its own on the y axis.
            let (tw, th) = text_size(root, "inf", &font(15.0))?;
            root.draw(&Text::new("inf", (bounds.0 - tw - 8, y - th / 2), font(15.0))).map_err(|e| err(&e))?;
        }
    }
    if let Some((x, name)) = plot.x_marker {
        let px = chart.backend_coord(&(x, y_range.end)).0;
        dashed(root, (px, bounds.1), (px, bounds.3), GREY)?;
        lines.push(segment((px, bounds.1), (px, bounds.3)));
        if text {
            // Beside the line at the top or at the bottom, wherever it hides fewer points.
            let (tw, th) = text_size(root, name, &font(14.0))?;
            let candidates = [
                (px + 6, bounds.1 + 4),
                (px - 6 - tw, bounds.1 + 4),
                (px + 6, bounds.3 - th - 4),
                (px - 6 - tw, bounds.3 - th - 4),
            ];
            labels.push(Label {
                text: name.to_string(),
                size: (tw, th),
                candidates: candidates.to_vec(),
                anchor: None,
                front: false,
                marker: true,
            });
        }
    }

    // The front as a staircase: the best quality reachable within each time budget, out to
    // the right edge (nothing slower does better).
    let mut front: Vec<(f64, f64)> = drawable.iter().filter(|p| p.front).map(|p| (p.x, y_of(p.y))).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut stairs = Vec::new();
    for (i, &(x, y)) in front.iter().enumerate() {
        if i > 0 {
            stairs.push((x, front[i - 1].1));
        }
        stairs.push((x, y));
    }
    if let Some(&(_, y)) = front.last() {
        stairs.push((x_end, y));
    }
    let stairs: Vec<(i32, i32)> = stairs.iter().map(|c| chart.backend_coord(c)).collect();
    lines.extend(stairs.windows(2).map(|w| segment(w[0], w[1])));
    root.draw(&PathElement::new(stairs, FRONT.mix(0.6).stroke_width(2))).map_err(|e| err(&e))?;

    for p in &drawable {
        let style = if p.front { FRONT.filled() } else { POINT.mix(0.8).filled() };
        root.draw(&Circle::new(at(p), if p.front { 6 } else { 4 }, style)).map_err(|e| err(&e))?;
    }
    if !text {
        return Ok(());
    }

    // The legend goes in the first corner free of points (bottom right, where slow and
    // inaccurate configurations are rare, first).
    let (lw, lh) = (124, 50);
    let corners: [Rect; 4] = [
        (bounds.2 - 8 - lw, bounds.3 - 8 - lh, bounds.2 - 8, bounds.3 - 8),
        (bounds.2 - 8 - lw, bounds.1 + 8, bounds.2 - 8, bounds.1 + 8 + lh),
        (bounds.0 + 8, bounds.3 - 8 - lh, bounds.0 + 8 + lw, bounds.3 - 8),
        (bounds.0 + 8, bounds.1 + 8, bounds.0 + 8 + lw, bounds.1 + 8 + lh),
    ];
    let hidden = |r: &Rect| {
        drawable
            .iter()
            .filter(|p| {
                let (x, y) = at(p);
                x >= r.0 - 8 && x <= r.2 + 8 && y >= r.1 - 8 && y <= r.3 + 8
            })
            .count()
    };
    let legend = corners.iter().copied().min_by_key(|r| hidden(r)).unwrap_or(corners[0]);
    root.draw(&Rectangle::new([(legend.0, legend.1), (legend.2, legend.3)], WHITE.filled()))
        .map_err(|e| err(&e))?;
    root.draw(&Rectangle::new([(legend.0, legend.1), (legend.2, legend.3)], GREY.stroke_width(1)))
        .map_err(|e| err(&e))?;
    for (i, (c, name)) in [(FRONT, "Pareto front"), (POINT, "dominated")].iter().enumerate() {
        let y = legend.1 + 13 + 22 * i as i32;
        root.draw(&Circle::new((legend.0 + 14, y), 5, c.filled())).map_err(|e| err(&e))?;
        root.draw(&Text::new(name.to_string(), (legend.0 + 26, y - 8), font(14.0))).map_err(|e| err(&e))?;
    }

    // Front labels first: they matter most and get the best places.
    let mut order: Vec<&&Point> = drawable.iter().filter(|p| !p.label.is_empty()).collect();
    order.sort_by_key(|p| !p.front);
    for p in order {
        let (tw, th) = text_size(root, &p.label, &font(13.0))?;
        labels.push(Label::around(&p.label, at(p), (tw, th), p.front));
    }
    let mut taken: Vec<Rect> = drawable
        .iter()
        .map(|p| {
            let (x, y) = at(p);
            (x - 5, y - 5, x + 5, y + 5)
        })
        .collect();
    taken.push(legend);
    taken.extend(lines);
    for l in labels {
        let (lx, ly) = l.place(&taken, bounds);
        let (tw, th) = l.size;
        taken.push((lx, ly, lx + tw, ly + th));
        if let Some((ax, ay)) = l.anchor {
            // A label pushed away from its point gets a leader line to it.
            let (cx, cy) = (ax.clamp(lx, lx + tw), ay.clamp(ly, ly + th));
            if (cx - ax).abs() + (cy - ay).abs() > 14 {
                root.draw(&PathElement::new(vec![(ax, ay), (cx, cy)], GREY.stroke_width(1)))
                    .map_err(|e| err(&e))?;
            }
        }
        let color = if l.marker {
            GREY
        } else if l.front {
            RGBColor(140, 25, 20)
        } else {
            RGBColor(40, 40, 40)
        };
        let size = if l.marker { 14.0 } else { 13.0 };
        root.draw(&Text::new(l.text, (lx, ly), font(size).color(&color))).map_err(|e| err(&e))?;
    }
    Ok(())
}

/// A pixel rectangle: left, top, right, bottom.
type Rect = (i32, i32, i32, i32);

/// A text label to place at the best of its candidate positions (top-left corners).
struct Label {
    text: String,
    size: (i32, i32),
    candidates: Vec<(i32, i32)>,
    /// The point it labels.
    anchor: Option<(i32, i32)>,
    front: bool,
    marker: bool,
}

impl Label {
    /// A point's label: beside the point in eight directions, then stacked further above and
    /// below it (with a leader line) when those are taken.
    fn around(text: &str, (x, y): (i32, i32), (tw, th): (i32, i32), front: bool) -> Self {
        let mut c = vec![
            (x + 8, y - th - 6),
            (x + 8, y + 6),
            (x - tw - 8, y - th - 6),
            (x - tw - 8, y + 6),
            (x + 10, y - th / 2),
            (x - tw - 10, y - th / 2),
            (x - tw / 2, y - th - 10),
            (x - tw / 2, y + 10),
        ];
        for k in 1..=6 {
            let dy = k * (th + 4);
            for dx in [8, -tw - 8, -tw / 2] {
                c.push((x + dx, y - th - 6 - dy));
                c.push((x + dx, y + 6 + dy));
            }
        }
        Self {
            text: text.to_string(),
            size: (tw, th),
            candidates: c,
            anchor: Some((x, y)),
            front,
            marker: false,
        }
    }

    /// The first candidate inside `bounds` that overlaps nothing in `taken`; failing that, the
    /// least overlapping one.
    fn place(&self, taken: &[Rect], bounds: Rect) -> (i32, i32) {
        let (tw, th) = self.size;
        let overlap = |a: &Rect, b: &Rect| {
            let w = (a.2.min(b.2) - a.0.max(b.0)).max(0);
            let h = (a.3.min(b.3) - a.1.max(b.1)).max(0);
            i64::from(w) * i64::from(h)
        };
        let cost = |&(lx, ly): &(i32, i32)| {
            // With a few pixels of air around the text.
            let r = (lx - 3, ly - 2, lx + tw + 3, ly + th + 2);
            let outside = lx < bounds.0 || ly < bounds.1 || r.2 > bounds.2 || r.3 > bounds.3;
            (outside, taken.iter().map(|t| overlap(t, &r)).sum::<i64>())
        };
        let mut best = self.candidates[0];
        let mut best_cost = cost(&best);
        for c in &self.candidates[1..] {
            let k = cost(c);
            if best_cost == (false, 0) {
                break;
            }
            if k < best_cost {
                (best, best_cost) = (*c, k);
            }
        }
        best
    }
}

fn text_size(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    text: &str,
    font: &FontDesc,
) -> Result<(i32, i32)> {
    let (w, h) = root
        .estimate_text_size(text, &TextStyle::from(font.clone()))
        .map_err(|e| anyhow!("cannot draw the plot: {e}"))?;
    Ok((w as i32, h as i32))
}

/// A dashed line between two pixels (horizontal or vertical).
fn dashed(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    from: (i32, i32),
    to: (i32, i32),
    color: impl Into<ShapeStyle>,
) -> Result<()> {
    let style: ShapeStyle = color.into();
    let style = style.stroke_width(2);
    let len = (to.0 - from.0).abs().max((to.1 - from.1).abs());
    let (dash, gap) = (6, 6);
    let mut t = 0;
    while t < len {
        let e = (t + dash).min(len);
        let lerp =
            |s: i32| (from.0 + (to.0 - from.0) * s / len.max(1), from.1 + (to.1 - from.1) * s / len.max(1));
        root.draw(&PathElement::new(vec![lerp(t), lerp(e)], style))
            .map_err(|e| anyhow!("cannot draw the plot: {e}"))?;
        t += dash + gap;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const INF: f64 = f64::INFINITY;
    const NAN: f64 = f64::NAN;

    #[test]
    fn front_of_a_simple_trade_off() {
        // (ms, dB): b is dominated by a (slower and worse); c is slower but better.
        let pts = [(10.0, 40.0), (20.0, 35.0), (30.0, 50.0), (5.0, 30.0)];
        assert_eq!(pareto_front(&pts), [true, false, true, true]);
        assert!(pareto_front(&[]).is_empty());
        assert_eq!(pareto_front(&[(1.0, 2.0)]), [true]);
    }

    #[test]
    fn ties() {
        // Identical points are all on the front; equal time with lower quality, or equal
        // quality at a higher time, is dominated.
        assert_eq!(pareto_front(&[(10.0, 40.0), (10.0, 40.0)]), [true, true]);
        assert_eq!(pareto_front(&[(10.0, 40.0), (10.0, 39.0)]), [true, false]);
        assert_eq!(pareto_front(&[(10.0, 40.0), (11.0, 40.0)]), [true, false]);
        assert_eq!(pareto_front(&[(10.0, 40.0), (10.0, 40.0), (12.0, 40.0)]), [true, true, false]);
    }

    #[test]
    fn infinite_and_nan_quality() {
        // inf dB (identical to the reference) is the best quality: it dominates anything
        // slower, and only something faster keeps its own place.
        assert_eq!(pareto_front(&[(10.0, INF), (20.0, 60.0), (5.0, 30.0)]), [true, false, true]);
        assert_eq!(pareto_front(&[(10.0, INF), (10.0, INF), (12.0, INF)]), [true, true, false]);
        // NaN is never on the front and dominates nothing, even when fastest.
        assert_eq!(pareto_front(&[(1.0, NAN), (10.0, 40.0), (20.0, 30.0)]), [false, true, false]);
        assert_eq!(pareto_front(&[(1.0, NAN)]), [false]);
        // A non-finite time neither.
        assert_eq!(pareto_front(&[(NAN, 50.0), (INF, 60.0), (10.0, 40.0)]), [false, false, true]);
    }

    /// Both axis kinds, an infinite value, labels and the marker draw without error, with and
    /// without text, and the PNG decodes to the requested size.
    #[test]
    fn writes_png_with_and_without_text() {
        let dir = tempfile::tempdir().unwrap();
        let pts = |xs: &[f64]| -> Vec<Point> {
            xs.iter()
                .enumerate()
                .map(|(i, &x)| Point {
                    x,
                    y: if i == 2 { INF } else { 30.0 + i as f64 },
                    label: format!("p{i}"),
                    front: i % 2 == 0,
                })
                .collect()
        };
        for (name, xs) in [("lin", vec![10.0, 12.0, 15.0]), ("log", vec![1.0, 50.0, 400.0])] {
            for text in [false, true] {
                if text && register_font().is_err() {
                    continue;
                }
                let points = pts(&xs);
                let plot = Plot {
                    title: "t",
                    x_name: "x",
                    y_name: "y",
                    points: &points,
                    x_marker: Some((20.0, "reference")),
                    size: (320, 240),
                };
                let p = dir.path().join(format!("{name}-{text}.png"));
                write_png(&p, &plot, text).unwrap();
                let img = image::open(&p).unwrap();
                assert_eq!((img.width(), img.height()), (320, 240));
            }
        }
    }
}
