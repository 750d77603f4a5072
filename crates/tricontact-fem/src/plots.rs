//! PNG line and scatter charts (plotters, bitmap backend) for the result folder.
//!
//! One drawing routine, [`chart`], serves every plot: a title, axis labels and a list of
//! [`Series`] drawn as lines or as points. A logarithmic y axis is drawn as `log₁₀ y` with tick
//! labels `1e<k>`, so all charts share one coordinate type. Text uses the DejaVu Sans font
//! embedded in the crate (`assets/`, Bitstream Vera licence), so plotting needs no system fonts.
//! Files are written atomically ([`write_atomic_with`]), like every other result file.
//!
//! Errors are one line, `cannot write plot <path>: <reason>`: a name not ending in `.png` is
//! refused before drawing, and an unwritable path gives the operating system's reason (the file is
//! created before drawing, so the backend's own error, a debug dump, is rarely seen).

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::atomic::write_atomic_with;
use crate::error::{FemError, Result};

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// The format of every chart, chosen by the bitmap backend from the file name.
const EXTENSION: &str = "png";

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// Polyline through the points.
    Line,
    /// A filled circle per point.
    Points,
}

/// One data series of a chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub label: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
    /// Line or points.
    pub mark: Mark,
}

impl Series {
    /// A polyline.
    #[must_use]
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            mark: Mark::Line,
        }
    }

    /// A scatter of points.
    #[must_use]
    pub fn points(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            mark: Mark::Points,
        }
    }

    /// Whether a point of the series would be drawn (finite; positive `y` on a log axis).
    #[must_use]
    pub fn is_drawn(&self, log_y: bool) -> bool {
        self.points.iter().any(|&p| drawn(p, log_y))
    }
}

/// Axis titles and scale of a chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Axes<'a> {
    /// Chart title.
    pub title: &'a str,
    /// x-axis label.
    pub x: &'a str,
    /// y-axis label.
    pub y: &'a str,
    /// Logarithmic y axis (non-positive values are dropped).
    pub log_y: bool,
    /// Legend in the lower right corner instead of the upper right (rising curves).
    pub legend_low: bool,
}

const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Whether the point `p` is drawn: finite, and positive `y` on a log axis.
fn drawn(p: (f64, f64), log_y: bool) -> bool {
    p.0.is_finite() && p.1.is_finite() && (!log_y || p.1 > 0.0)
}

/// `cannot write plot <path>: <reason>`.
fn plot_error(path: &Path, reason: impl std::fmt::Display) -> FemError {
    FemError::Output(format!("cannot write plot {}: {reason}", path.display()))
}

/// The operating system's message of `e`, without the ` (os error N)` suffix.
fn io_reason(e: &std::io::Error) -> String {
    let text = e.to_string();
    e.raw_os_error()
        .and_then(|code| text.strip_suffix(&format!(" (os error {code})")))
        .map_or_else(|| text.clone(), str::to_string)
}

/// Refuses a chart path whose name does not end in `.png` (any case).
///
/// # Errors
/// [`FemError::Output`] naming the path.
pub fn check_png(path: &Path) -> Result<()> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(EXTENSION))
    {
        Ok(())
    } else {
        Err(plot_error(
            path,
            format_args!("the file name must end in .{EXTENSION}"),
        ))
    }
}

/// Finite data range with a margin; `(0, 1)` when empty.
fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if lo > hi {
        return (0.0, 1.0);
    }
    if log {
        return (lo.floor(), hi.ceil().max(lo.floor() + 1.0));
    }
    // Each end scaled before the difference, and the padded ends kept finite: a span beyond
    // `f64::MAX` made an infinite range, on which the chart never finished.
    let pad = if hi > lo {
        0.05 * hi - 0.05 * lo
    } else {
        0.5 * hi.abs().max(1.0)
    };
    (
        (lo - pad).max(f64::MIN / 2.0),
        (hi + pad).min(f64::MAX / 2.0),
    )
}

/// A tick label with at most four significant digits, trailing zeros removed.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        return format!("{v:.2e}");
    }
    let digits = if a >= 1.0 {
        3 - (a.log10().floor() as i32).min(3)
    } else {
        4
    };
    let s = format!("{v:.*}", digits.max(0) as usize);
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Draws `series` into a PNG at `path` (written atomically).
///
/// # Errors
/// A name not ending in `.png`, drawing or file errors (one line naming `path`).
pub fn chart(path: &Path, axes: &Axes<'_>, series: &[Series]) -> Result<()> {
    check_png(path)?;
    REGISTER.call_once(|| {
        // The embedded font is valid; a failure only means default glyphs are missing.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
    let data: Vec<Vec<(f64, f64)>> = series
        .iter()
        .map(|s| {
            s.points
                .iter()
                .filter(|&&p| drawn(p, axes.log_y))
                .map(|&(x, y)| (x, if axes.log_y { y.log10() } else { y }))
                .collect()
        })
        .collect();
    let (x0, x1) = range(data.iter().flatten().map(|p| p.0), false);
    let (y0, y1) = range(data.iter().flatten().map(|p| p.1), axes.log_y);
    write_atomic_with(path, |tmp| {
        // An unwritable folder fails here with its I/O error, not after drawing.
        std::fs::File::create(tmp).map_err(|e| FemError::io(tmp, e))?;
        let root = BitMapBackend::new(tmp, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_error(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(axes.title, ("sans-serif", 24))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| plot_error(path, e))?;
        let log_label = |v: &f64| format!("1e{v:.0}");
        let lin_label = |v: &f64| tick(*v);
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(axes.x)
            .y_desc(axes.y)
            .label_style(("sans-serif", 16))
            .x_label_formatter(&lin_label)
            .y_label_formatter(&lin_label);
        if axes.log_y {
            mesh.y_labels((y1 - y0) as usize + 1)
                .y_label_formatter(&log_label);
        }
        mesh.draw().map_err(|e| plot_error(path, e))?;
        for (k, (s, pts)) in series.iter().zip(&data).enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let drawn = match s.mark {
                Mark::Line => chart
                    .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                    .map_err(|e| plot_error(path, e))?,
                Mark::Points => chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(|e| plot_error(path, e))?,
            };
            drawn.label(s.label.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3))
            });
        }
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 16))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(if axes.legend_low {
                SeriesLabelPosition::LowerRight
            } else {
                SeriesLabelPosition::UpperRight
            })
            .draw()
            .map_err(|e| plot_error(path, e))?;
        root.present().map_err(|e| plot_error(path, e))
    })
    .map_err(|e| match e {
        FemError::Io { source, .. } => plot_error(path, io_reason(&source)),
        other => other,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_a_png_with_log_axis_and_skips_bad_points() {
        let dir = std::env::temp_dir().join(format!("tricontact-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("chart.png");
        let axes = Axes {
            title: "residual",
            x: "iteration",
            y: "relative residual",
            log_y: true,
            legend_low: false,
        };
        let series = [
            Series::line(
                "inc 1",
                vec![(0.0, 1.0), (1.0, 1e-3), (2.0, 1e-9), (3.0, 0.0)],
            ),
            Series::points("nan", vec![(f64::NAN, 1.0), (1.0, f64::INFINITY)]),
        ];
        chart(&path, &axes, &series).expect("chart");
        let bytes = std::fs::read(&path).expect("png written");
        assert_eq!(&bytes[1..4], b"PNG");
        assert!(!dir.join("chart.tmp.png").exists());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn only_png_names_are_accepted() {
        assert!(check_png(Path::new("a/b.png")).is_ok());
        assert!(check_png(Path::new("B.PNG")).is_ok());
        for bad in ["p.txt", "png", "p.png.bak"] {
            let e = check_png(Path::new(bad)).expect_err(bad).to_string();
            assert!(
                e.ends_with(&format!(
                    "cannot write plot {bad}: the file name must end in .png"
                )),
                "{e}"
            );
        }
        let e = std::io::Error::from_raw_os_error(2);
        assert_eq!(io_reason(&e), "No such file or directory");
        assert_eq!(io_reason(&std::io::Error::other("full")), "full");
    }

    #[test]
    fn ranges_are_padded_and_finite() {
        assert_eq!(range(std::iter::empty(), false), (0.0, 1.0));
        let (lo, hi) = range([2.0, 2.0].into_iter(), false);
        assert!(lo < 2.0 && hi > 2.0);
        assert_eq!(range([-9.5, 0.0].into_iter(), true), (-10.0, 0.0));
        // A span beyond f64::MAX: padded, finite, and its width too.
        let (lo, hi) = range([-1e308, 1e308].into_iter(), false);
        assert!(lo < 0.0 && hi > 0.0 && (hi - lo).is_finite(), "{lo} {hi}");
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick(2000.0), "2000");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(2.5e6), "2.50e6");
    }
}
