//! Charts of the lab (plotters): speed against accuracy with its Pareto front, error
//! against a swept parameter, and bars. PNG (bitmap) and SVG from the same drawing code.
//! Text uses the Ubuntu font that egui ships, so no system font is needed.

use crate::{Error, Result};

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

/// Writes `$path.png` and `$path.svg` of `$size`, both drawn by `$body` on `$root`.
macro_rules! png_and_svg {
    ($path:expr, $size:expr, |$root:ident| $body:expr) => {{
        fonts();
        draw_png(&$path.with_extension("png"), $size, |$root| $body)?;
        draw_svg(&$path.with_extension("svg"), $size, |$root| $body)
    }};
}

/// A named set of points.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// (x, y) points.
    pub points: Vec<(f64, f64)>,
}

const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The colour of the `i`-th series.
pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

pub(crate) fn fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

fn err(e: impl std::fmt::Debug) -> Error {
    Error::Chart {
        what: "chart",
        detail: format!("{e:?}"),
    }
}

/// Axis range covering `values` with a margin; on a log axis the range stays positive.
fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let v: Vec<f64> = values
        .filter(|v| v.is_finite() && (!log || *v > 0.0))
        .collect();
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if !lo.is_finite() {
        return if log { (0.01, 1.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 1.6, hi * 1.6)
    } else {
        let pad = ((hi - lo) * 0.08).max(1e-3);
        (
            (lo - pad)
                .min(0.0)
                .max(if lo >= 0.0 { 0.0 } else { lo - pad }),
            hi + pad,
        )
    }
}

/// The points not dominated by another (smaller x and smaller y are better), by x.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for (x, y) in p {
        if y < best {
            front.push((x, y));
            best = y;
        }
    }
    front
}

/// Smallest FLIP the speed/accuracy chart shows (its y axis is logarithmic; 0 is drawn here).
pub const FLIP_FLOOR: f64 = 1e-4;

/// Speed against accuracy: small markers per scene, large ones for the suite means, the
/// Pareto front through the means. Writes `path.png` and `path.svg`.
pub fn speed_vs_accuracy(
    path: &Path,
    title: &str,
    per_scene: &[Series],
    means: &[Series],
) -> Result<()> {
    png_and_svg!(path, (1000, 640), |root| scatter(
        root, title, per_scene, means
    ))
}

/// Draws with `f` into a bitmap in memory and writes it to `path` as a PNG, in one
/// checked write: plotters' own file output drops a buffered writer, losing the error of
/// its last flush (a full disk).
fn draw_png(
    path: &Path,
    size: (u32, u32),
    f: impl FnOnce(DrawingArea<BitMapBackend<'_>, Shift>) -> Result<()>,
) -> Result<()> {
    let (w, h) = size;
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    f(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area())?;
    let rgba = rgb
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    voxel_render::Image {
        width: w,
        height: h,
        rgba,
    }
    .save_png(path)
    .map_err(Error::Render)
}

/// Draws with `f` into an SVG text in memory and writes it to `path` in one checked write.
fn draw_svg(
    path: &Path,
    size: (u32, u32),
    f: impl FnOnce(DrawingArea<SVGBackend<'_>, Shift>) -> Result<()>,
) -> Result<()> {
    let mut text = String::new();
    f(SVGBackend::with_string(&mut text, size).into_drawing_area())?;
    crate::files::write_file(path, text.as_bytes())
}

/// Log scales on both axes.
type LogLog = Cartesian2d<LogCoord<f64>, LogCoord<f64>>;

/// The frame of a speed/accuracy chart on a white `root`: log GPU ms across (`x_desc`),
/// log mean FLIP up to `y1` (below [`FLIP_FLOOR`] drawn there), axes and mesh drawn.
fn flip_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    (x0, x1): (f64, f64),
    y1: f64,
) -> Result<ChartContext<'a, DB, LogLog>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((x0..x1).log_scale(), (FLIP_FLOOR / 1.5..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("mean FLIP against the exact reference (log; 0 drawn at 1e-4)")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    Ok(chart)
}

/// Draws the legend of `chart` at `position` in `font_size` on white, framed.
fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font_size: u32,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(position)
        .label_font(("sans-serif", font_size))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)
}

fn scatter<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    per_scene: &[Series],
    means: &[Series],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let floor = |(x, y): (f64, f64)| (x, y.max(FLIP_FLOOR));
    let all = || {
        per_scene
            .iter()
            .chain(means)
            .flat_map(|s| s.points.iter().copied())
            .map(floor)
    };
    let x = range(all().map(|p| p.0), true);
    let (_, y1) = range(all().map(|p| p.1), true);
    let x_desc = "GPU ms per frame for the translucent work (log scale)";
    let mut chart = flip_chart(&root, title, x_desc, x, y1)?;
    for (i, s) in per_scene.iter().enumerate() {
        let c = color(i);
        chart
            .draw_series(
                s.points
                    .iter()
                    .map(move |&p| Circle::new(floor(p), 3, c.mix(0.55).filled())),
            )
            .map_err(err)?;
    }
    for (i, s) in means.iter().enumerate() {
        let c = color(i);
        chart
            .draw_series(
                s.points
                    .iter()
                    .map(move |&p| Circle::new(floor(p), 8, c.filled())),
            )
            .map_err(err)?
            .label(s.name.clone())
            .legend(move |(x, y)| Circle::new((x, y), 6, c.filled()));
    }
    let points: Vec<(f64, f64)> = means
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .collect();
    let front: Vec<(f64, f64)> = pareto_front(&points).into_iter().map(floor).collect();
    chart
        .draw_series(LineSeries::new(front, BLACK.stroke_width(2)))
        .map_err(err)?
        .label("Pareto front (suite means)")
        .legend(|(x, y)| PathElement::new(vec![(x - 10, y), (x + 10, y)], BLACK.stroke_width(2)));
    legend(&mut chart, SeriesLabelPosition::UpperRight, 14)?;
    root.present().map_err(err)
}

/// Error against a swept parameter, one line per technique. Writes `path.png` and `.svg`.
pub fn sweep(path: &Path, title: &str, x_desc: &str, log_x: bool, series: &[Series]) -> Result<()> {
    line_chart(
        path,
        title,
        (x_desc, "mean FLIP against the exact reference"),
        log_x,
        series,
    )
}

/// Any quantity against another, one line per series (points marked when there are few).
/// Writes `path.png` and `path.svg`.
pub fn line_chart(
    path: &Path,
    title: &str,
    (x_desc, y_desc): (&str, &str),
    log_x: bool,
    series: &[Series],
) -> Result<()> {
    let axes = (x_desc, y_desc);
    png_and_svg!(path, (900, 560), |root| lines(
        root, title, axes, log_x, series
    ))
}

fn lines<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    (x_desc, y_desc): (&str, &str),
    log_x: bool,
    series: &[Series],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let all = || series.iter().flat_map(|s| s.points.iter().copied());
    let (x0, x1) = range(all().map(|p| p.0), log_x);
    let (_, y1) = range(all().map(|p| p.1), false);
    macro_rules! builder {
        () => {
            ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 20))
                .margin(14)
                .x_label_area_size(44)
                .y_label_area_size(64)
        };
    }
    macro_rules! body {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(x_desc)
                .y_desc(y_desc)
                .label_style(("sans-serif", 14))
                .draw()
                .map_err(err)?;
            for (i, s) in series.iter().enumerate() {
                let c = color(i);
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                    .map_err(err)?
                    .label(s.name.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x - 10, y), (x + 10, y)], c.stroke_width(2))
                    });
                if s.points.len() <= 100 {
                    chart
                        .draw_series(s.points.iter().map(move |&p| Circle::new(p, 3, c.filled())))
                        .map_err(err)?;
                }
            }
            legend(&mut chart, SeriesLabelPosition::UpperLeft, 13)?;
        }};
    }
    if log_x {
        body!(
            builder!()
                .build_cartesian_2d((x0..x1).log_scale(), 0.0..y1)
                .map_err(err)?
        );
    } else {
        body!(
            builder!()
                .build_cartesian_2d(x0..x1, 0.0..y1)
                .map_err(err)?
        );
    }

    root.present().map_err(err)
}

/// One bar per name. Writes `path.png` and `path.svg`.
pub fn bars(path: &Path, title: &str, y_desc: &str, values: &[(String, f64)]) -> Result<()> {
    png_and_svg!(path, (900, 520), |root| bar_body(
        root, title, y_desc, values
    ))
}

fn bar_body<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    y_desc: &str,
    values: &[(String, f64)],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let (_, y1) = range(values.iter().map(|v| v.1), false);
    let n = values.len().max(1) as i32;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(14)
        .x_label_area_size(70)
        .y_label_area_size(64)
        .build_cartesian_2d(0..n, 0.0..y1)
        .map_err(err)?;
    let names: Vec<String> = values.iter().map(|v| v.0.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(values.len().max(1))
        .x_label_formatter(&|i| names.get(*i as usize).cloned().unwrap_or_default())
        .x_label_style(
            ("sans-serif", 12)
                .into_font()
                .transform(FontTransform::Rotate90),
        )
        .y_desc(y_desc)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(values.iter().enumerate().map(|(i, (_, v))| {
            let i = i as i32;
            Rectangle::new([(i, 0.0), (i + 1, *v)], color(i as usize).filled())
        }))
        .map_err(err)?;
    root.present().map_err(err)
}

/// A technique's spread: p10, median and p90 of its time (x) and of its error (y).
#[derive(Clone, Debug, PartialEq)]
pub struct Spread {
    /// Legend text.
    pub name: String,
    /// p10, p50, p90 of the x value.
    pub x: [f64; 3],
    /// p10, p50, p90 of the y value.
    pub y: [f64; 3],
}

/// Speed against accuracy over a distribution of scenes: per technique a marker at the
/// medians and bars (whiskers) from p10 to p90 of each. Log axes; FLIP below
/// [`FLIP_FLOOR`] is drawn there. Writes `path.png` and `path.svg`.
pub fn speed_vs_accuracy_spread(path: &Path, title: &str, spreads: &[Spread]) -> Result<()> {
    png_and_svg!(path, (1000, 640), |root| spread_body(root, title, spreads))
}

fn spread_body<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    spreads: &[Spread],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let fy = |y: f64| y.max(FLIP_FLOOR);
    let x = range(spreads.iter().flat_map(|s| s.x), true);
    let (_, y1) = range(spreads.iter().flat_map(|s| s.y.map(fy)), true);
    let x_desc =
        "GPU ms per frame for the translucent work (log; bars p10 to p90, marker at the median)";
    let mut chart = flip_chart(&root, title, x_desc, x, y1)?;
    for (i, s) in spreads.iter().enumerate() {
        let c = color(i);
        let (mx, my) = (s.x[1], fy(s.y[1]));
        let style = c.stroke_width(3);
        chart
            .draw_series([
                PathElement::new(vec![(s.x[0], my), (s.x[2], my)], style),
                PathElement::new(vec![(mx, fy(s.y[0])), (mx, fy(s.y[2]))], style),
            ])
            .map_err(err)?;
        chart
            .draw_series([Circle::new((mx, my), 7, c.filled())])
            .map_err(err)?
            .label(s.name.clone())
            .legend(move |(x, y)| Circle::new((x, y), 6, c.filled()));
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight, 14)?;
    root.present().map_err(err)
}

/// Histograms as small multiples: one panel per series, one bar per bin (`bins` labels
/// them), heights as shares of the series' total. Writes `path.png` and `path.svg`.
pub fn histograms(
    path: &Path,
    title: &str,
    bins: &[String],
    series: &[(String, Vec<usize>)],
) -> Result<()> {
    let cols = 3usize;
    let rows = series.len().div_ceil(cols).max(1);
    let size = (1100, 60 + 260 * rows as u32);
    png_and_svg!(path, size, |root| histogram_body(
        root,
        title,
        bins,
        series,
        (rows, cols)
    ))
}

fn histogram_body<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    bins: &[String],
    series: &[(String, Vec<usize>)],
    (rows, cols): (usize, usize),
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(err)?;
    let panels = root.split_evenly((rows, cols));
    let n = bins.len().max(1) as i32;
    for (i, ((name, counts), area)) in series.iter().zip(panels.iter()).enumerate() {
        let total = counts.iter().sum::<usize>().max(1) as f64;
        let mut chart = ChartBuilder::on(area)
            .caption(name, ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d((0..n).into_segmented(), 0.0..1.0)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(bins.len().max(1))
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => bins.get(*i as usize).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            .y_labels(5)
            .y_label_formatter(&|v| format!("{:.0}%", v * 100.0))
            .x_desc(if i / cols == rows - 1 {
                "largest error (1/255)"
            } else {
                ""
            })
            .label_style(("sans-serif", 10))
            .draw()
            .map_err(err)?;
        let c = color(i);
        chart
            .draw_series(counts.iter().enumerate().map(|(b, v)| {
                let b = b as i32;
                Rectangle::new(
                    [
                        (SegmentValue::Exact(b), 0.0),
                        (SegmentValue::Exact(b + 1), *v as f64 / total),
                    ],
                    c.filled(),
                )
            }))
            .map_err(err)?;
    }
    root.present().map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let p = [
            (1.0, 0.5),
            (2.0, 0.6),
            (3.0, 0.1),
            (0.5, 0.9),
            (4.0, 0.0),
            (5.0, 0.0),
        ];
        assert_eq!(
            pareto_front(&p),
            vec![(0.5, 0.9), (1.0, 0.5), (3.0, 0.1), (4.0, 0.0)]
        );
    }

    #[test]
    fn charts_are_written() {
        let dir = std::env::temp_dir().join(format!("voxel_charts_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let s = vec![Series {
            name: "a".into(),
            points: vec![(0.5, 0.1), (2.0, 0.05)],
        }];
        speed_vs_accuracy(&dir.join("sva"), "t", &s, &s).unwrap();
        speed_vs_accuracy_spread(
            &dir.join("spread"),
            "t",
            &[Spread {
                name: "a".into(),
                x: [0.5, 1.0, 2.0],
                y: [0.0, 0.01, 0.1],
            }],
        )
        .unwrap();
        histograms(
            &dir.join("hist"),
            "t",
            &["0".into(), "1".into()],
            &[("a".into(), vec![3, 1]), ("b".into(), vec![0, 4])],
        )
        .unwrap();
        sweep(&dir.join("sweep"), "t", "x", true, &s).unwrap();
        bars(
            &dir.join("bars"),
            "t",
            "y",
            &[("a".into(), 1.0), ("b".into(), 2.0)],
        )
        .unwrap();
        for f in [
            "sva.png",
            "sva.svg",
            "sweep.png",
            "sweep.svg",
            "bars.png",
            "bars.svg",
            "spread.png",
            "spread.svg",
            "hist.png",
            "hist.svg",
        ] {
            let len = std::fs::metadata(dir.join(f)).unwrap().len();
            assert!(len > 1000, "{f}: {len} bytes");
        }
        let _ = std::fs::remove_dir_all(dir);
    }

    /// A chart that cannot be written (a folder in the way of the PNG, then of
    /// the SVG) is an error naming the file, not a success.
    #[test]
    fn a_failed_chart_write_is_an_error_naming_the_file() {
        let dir = std::env::temp_dir().join(format!("voxel_charts_fail_{}", std::process::id()));
        let s = vec![Series {
            name: "a".into(),
            points: vec![(0.5, 0.1), (2.0, 0.05)],
        }];
        for blocked in ["sva.png", "sva.svg"] {
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(dir.join(blocked)).unwrap();
            let e = speed_vs_accuracy(&dir.join("sva"), "t", &s, &s)
                .unwrap_err()
                .to_string();
            assert!(e.contains(blocked), "{blocked}: {e}");
        }
        let _ = std::fs::remove_dir_all(dir);
    }
}
