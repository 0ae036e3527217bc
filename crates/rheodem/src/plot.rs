//! Line plots and heat maps, rendered to SVG (heat maps also to PNG) with a bundled font
//! (DejaVu Sans), so that figures need no system font libraries.

use plotters::prelude::*;
use std::sync::Once;

mod heat_map;
pub use heat_map::HeatMap;

/// One named curve: `(x, y)` points joined by lines.
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// The points.
    pub points: &'a [(f64, f64)],
    /// `None`: a solid line in the colour of its own index. `Some(k)`: a dashed line in the
    /// colour of curve and marker set `k` (a fit beside the published law of those points).
    pub dashed_as: Option<usize>,
}

/// Named measured points `(x, y, standard error of y)`, drawn as dots with error bars in
/// the colour of the curve of the same index.
pub struct Markers<'a> {
    /// Legend label.
    pub label: &'a str,
    /// The points.
    pub points: &'a [(f64, f64, f64)],
}

/// Axis labels and title of a plot.
pub struct Labels<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// Label of the horizontal axis.
    pub x: &'a str,
    /// Label of the vertical axis.
    pub y: &'a str,
}

/// Colour of curve or marker set `k`: dark, well separated on white, then repeating.
fn colour(k: usize) -> RGBAColor {
    const COLOURS: [(u8, u8, u8); 6] = [
        (200, 30, 60),
        (30, 140, 60),
        (30, 80, 200),
        (230, 130, 0),
        (120, 60, 160),
        (90, 90, 90),
    ];
    let (r, g, b) = COLOURS[k % COLOURS.len()];
    RGBColor(r, g, b).to_rgba()
}

static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        // The bundled font is valid; a failure would only lose text, not the plot.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            include_bytes!("../assets/DejaVuSans.ttf"),
        );
    });
}

/// Renders the series as an SVG document, 800×560 pixels.
pub fn line_plot_svg(labels: &Labels<'_>, series: &[Series<'_>]) -> Result<String, String> {
    plot_svg(labels, series, &[])
}

/// Size of a rendered line plot (pixels).
const PLOT_SIZE: (u32, u32) = (800, 560);

/// Renders curves and measured points with error bars as an SVG document, 800×560 pixels.
/// Curve `k` and marker set `k` share a colour; marker sets beyond the curves get colours
/// of their own. A curve or marker set without points is not drawn (nor put in the legend).
pub fn plot_svg(
    labels: &Labels<'_>,
    series: &[Series<'_>],
    markers: &[Markers<'_>],
) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        draw_plot(&root, labels, series, markers)?;
    }
    Ok(svg)
}

/// [`plot_svg`] rendered as a PNG image (8-bit RGB).
///
/// # Errors
/// As [`plot_svg`], and a message when encoding fails.
pub fn plot_png(
    labels: &Labels<'_>,
    series: &[Series<'_>],
    markers: &[Markers<'_>],
) -> Result<Vec<u8>, String> {
    let mut rgb = vec![0u8; (PLOT_SIZE.0 * PLOT_SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, PLOT_SIZE).into_drawing_area();
        draw_plot(&root, labels, series, markers)?;
    }
    encode_png(&rgb, PLOT_SIZE)
}

/// Encodes an 8-bit RGB buffer of `size` pixels as PNG.
fn encode_png(rgb: &[u8], size: (u32, u32)) -> Result<Vec<u8>, String> {
    let mut png = Vec::new();
    let mut encoder = png::Encoder::new(&mut png, size.0, size.1);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(rgb).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(png)
}

/// Draws the plot of [`plot_svg`] on any backend.
fn draw_plot<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    labels: &Labels<'_>,
    series: &[Series<'_>],
    markers: &[Markers<'_>],
) -> Result<(), String> {
    register_font();
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let curve_points = series.iter().flat_map(|s| s.points.iter().copied());
    let marker_points = markers.iter().flat_map(|m| {
        m.points
            .iter()
            .flat_map(|&(x, y, e)| [(x, y - e.abs()), (x, y + e.abs())])
    });
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for (x, y) in curve_points.chain(marker_points) {
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !(x0.is_finite() && y0.is_finite()) {
        return Err("nothing to plot".into());
    }
    let pad = |a: f64, b: f64| {
        let d = if b > a {
            0.05 * (b - a)
        } else {
            a.abs().max(1.0) * 0.05
        };
        (a - d, b + d)
    };
    let ((x0, x1), (y0, y1)) = (pad(x0, x1), pad(y0, y1));
    // Headroom above the data for the legend (upper right), so that it hides nothing.
    let entries = (series.iter().filter(|s| !s.points.is_empty()).count()
        + markers.iter().filter(|m| !m.points.is_empty()).count()) as f64;
    let y1 = y1 + (y1 - y0) * (0.08 * entries).min(0.6);
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(root)
        .caption(labels.title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    // A curve without points is left out, keeping its colour for its markers.
    for (k, s) in series
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.points.is_empty())
    {
        let color = colour(s.dashed_as.unwrap_or(k));
        let style = color.stroke_width(2);
        match s.dashed_as {
            None => chart
                .draw_series(LineSeries::new(s.points.iter().copied(), style))
                .map_err(err)?
                .label(s.label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style)),
            Some(_) => chart
                .draw_series(DashedLineSeries::new(s.points.iter().copied(), 8, 5, style))
                .map_err(err)?
                .label(s.label)
                .legend(move |(x, y)| {
                    plotters::element::DashedPathElement::new(
                        vec![(x, y), (x + 20, y)],
                        5,
                        3,
                        style,
                    )
                }),
        };
    }
    for (k, m) in markers
        .iter()
        .enumerate()
        .filter(|(_, m)| !m.points.is_empty())
    {
        let color = colour(k);
        chart
            .draw_series(m.points.iter().map(|&(x, y, e)| {
                ErrorBar::new_vertical(x, y - e.abs(), y, y + e.abs(), color.stroke_width(2), 8)
            }))
            .map_err(err)?;
        chart
            .draw_series(
                m.points
                    .iter()
                    .map(|&(x, y, _)| Circle::new((x, y), 4, color.filled())),
            )
            .map_err(err)?
            .label(m.label)
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}
