//! Line plots and heat maps, rendered to SVG (heat maps also to PNG) with a bundled font
//! (DejaVu Sans), so that figures need no system font libraries.

use plotters::prelude::*;
use std::sync::Once;

mod heat_map;
pub mod rich;
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

/// Space above the plot for its title (pixels).
const TITLE_SPACE: u32 = 45;

/// A tick value as a reader writes it: no trailing zeros (`20`, not `20.0`), no negative
/// zero, and powers of ten for very large or small magnitudes.
pub fn tick_label(v: f64) -> String {
    let a = v.abs();
    if a < 1e-12 * 1e3f64.max(a) || a == 0.0 {
        return "0".into();
    }
    let trim = |t: String| {
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t
        }
    };
    if !(1e-3..1e5).contains(&a) {
        let t = format!("{v:.3e}");
        let (mantissa, exponent) = t.split_once('e').unwrap_or((&t, "0"));
        return format!("{}e{exponent}", trim(mantissa.to_string()));
    }
    // Six significant digits, then the zeros trimmed.
    let decimals = (5 - a.log10().floor() as i32).clamp(0, 9) as usize;
    let t = trim(format!("{v:.decimals$}"));
    if t == "-0" { "0".into() } else { t }
}

/// What a legend entry shows beside its label.
#[derive(Clone, Copy)]
pub(crate) enum LegendMark {
    /// A line in this colour, dashed or solid.
    Line(RGBAColor, bool),
    /// A dot in this colour.
    Dot(RGBAColor),
}

/// The title above the plot and the axis labels beside the plotting area (pixel ranges
/// `area`), with subscripts and superscripts ([`rich`]).
pub(crate) fn draw_labels<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    labels: &Labels<'_>,
    area: (std::ops::Range<i32>, std::ops::Range<i32>),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (w, h) = root.dim_in_pixel();
    let (xs, ys) = area;
    let centre = (w as i32 / 2, (TITLE_SPACE / 2) as i32);
    rich::draw(
        root,
        labels.title,
        centre,
        20.0,
        &BLACK,
        rich::Align::Centre,
        false,
    )?;
    let below = ((xs.start + xs.end) / 2, h as i32 - 14);
    rich::draw(
        root,
        labels.x,
        below,
        15.0,
        &BLACK,
        rich::Align::Centre,
        false,
    )?;
    let left = (16, (ys.start + ys.end) / 2);
    rich::draw(
        root,
        labels.y,
        left,
        15.0,
        &BLACK,
        rich::Align::Centre,
        true,
    )
}

/// The legend in the upper right corner (`corner`, pixels) of the plotting area, or in the
/// upper left (`corner` then that corner) when `from_left`.
pub(crate) fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    entries: &[(&str, LegendMark)],
    corner: (i32, i32),
    from_left: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    if entries.is_empty() {
        return Ok(());
    }
    const SIZE: f64 = 13.0;
    const ROW: i32 = 22;
    let text = entries
        .iter()
        .map(|(l, _)| rich::width(root, l, SIZE) as i32)
        .max()
        .unwrap_or(0);
    let (w, h) = (text + 50, ROW * entries.len() as i32 + 10);
    let x0 = if from_left {
        corner.0 + 10
    } else {
        corner.0 - w - 10
    };
    let y0 = corner.1 + 10;
    root.draw(&Rectangle::new(
        [(x0, y0), (x0 + w, y0 + h)],
        WHITE.mix(0.85).filled(),
    ))?;
    root.draw(&Rectangle::new([(x0, y0), (x0 + w, y0 + h)], BLACK))?;
    for (k, (label, mark)) in entries.iter().enumerate() {
        let y = y0 + 5 + ROW * k as i32 + ROW / 2;
        match *mark {
            LegendMark::Line(c, false) => root.draw(&PathElement::new(
                vec![(x0 + 8, y), (x0 + 32, y)],
                c.stroke_width(2),
            ))?,
            LegendMark::Line(c, true) => root.draw(&plotters::element::DashedPathElement::new(
                vec![(x0 + 8, y), (x0 + 32, y)],
                5,
                3,
                c.stroke_width(2),
            ))?,
            LegendMark::Dot(c) => root.draw(&Circle::new((x0 + 20, y), 4, c.filled()))?,
        }
        rich::draw(
            root,
            label,
            (x0 + 40, y - 8),
            SIZE,
            &BLACK,
            rich::Align::Left,
            false,
        )?;
    }
    Ok(())
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
        .margin(15)
        .margin_top(TITLE_SPACE)
        .x_label_area_size(55)
        .y_label_area_size(95)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| tick_label(*v))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    let mut legend: Vec<(&str, LegendMark)> = Vec::new();
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
                .map_err(err)?,
            Some(_) => chart
                .draw_series(DashedLineSeries::new(s.points.iter().copied(), 8, 5, style))
                .map_err(err)?,
        };
        legend.push((s.label, LegendMark::Line(color, s.dashed_as.is_some())));
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
            .map_err(err)?;
        legend.push((m.label, LegendMark::Dot(color)));
    }
    let (xs, ys) = chart.plotting_area().get_pixel_range();
    draw_labels(root, labels, (xs.clone(), ys.clone())).map_err(err)?;
    draw_legend(root, &legend, (xs.end, ys.start), false).map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::tick_label;

    #[test]
    fn tick_labels_read_as_written_by_hand() {
        assert_eq!(tick_label(20.0), "20");
        assert_eq!(tick_label(-0.0), "0");
        assert_eq!(tick_label(-1e-17), "0");
        assert_eq!(tick_label(0.30000000000000004), "0.3");
        assert_eq!(tick_label(-2.5), "-2.5");
        assert_eq!(tick_label(450000.0), "4.5e5");
        assert_eq!(tick_label(2.2e-4), "2.2e-4");
        assert_eq!(tick_label(0.0125), "0.0125");
    }
}
