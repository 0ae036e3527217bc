//! Heat maps of a field on a regular 2-D grid, with curves drawn over them and a colour bar,
//! rendered to SVG or PNG with the bundled font.

use super::{
    Labels, LegendMark, Series, TITLE_SPACE, colour as curve_colour, draw_labels, draw_legend,
    register_font, rich, tick_label,
};
use plotters::coord::Shift;
use plotters::prelude::*;

/// A scalar field on a regular grid of cell centres, to be drawn as coloured cells.
pub struct HeatMap<'a> {
    /// Title above the map.
    pub title: &'a str,
    /// Label of the horizontal axis.
    pub x: &'a str,
    /// Label of the vertical axis.
    pub y: &'a str,
    /// Label of the colour bar (the field and its unit).
    pub value: &'a str,
    /// Cell centres along the horizontal axis, ascending and evenly spaced.
    pub xs: &'a [f64],
    /// Cell centres along the vertical axis, ascending and evenly spaced.
    pub ys: &'a [f64],
    /// The field, `values[ix + xs.len() * iy]`; non-finite values are left blank.
    pub values: &'a [f64],
    /// Curves drawn over the map, the first in black and the rest in the line plots'
    /// colours, with the legend in the upper left; a non-finite point breaks a curve into
    /// pieces (for contours of several branches).
    pub overlays: &'a [Series<'a>],
}

/// Size of a rendered map (pixels).
const SIZE: (u32, u32) = (900, 520);

/// Width of the colour bar's area (pixels).
const BAR: u32 = 130;

/// The colour scale spans these quantiles of the finite values, so that a few extreme cells
/// (at the free surface, where `P → 0`) do not wash out the rest; values beyond it saturate.
const QUANTILES: (f64, f64) = (0.02, 0.98);

impl HeatMap<'_> {
    /// Checks the shape and returns the colour range `(lo, hi)`.
    fn range(&self) -> Result<(f64, f64), String> {
        if self.xs.len() < 2 || self.ys.len() < 2 {
            return Err("a heat map needs at least 2 × 2 cells".into());
        }
        if self.values.len() != self.xs.len() * self.ys.len() {
            return Err(format!(
                "{} values for a {} × {} grid",
                self.values.len(),
                self.xs.len(),
                self.ys.len()
            ));
        }
        let mut finite: Vec<f64> = self
            .values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if finite.is_empty() {
            return Err(format!("no finite values of {} to draw", self.value));
        }
        finite.sort_by(f64::total_cmp);
        let at = |q: f64| finite[((finite.len() - 1) as f64 * q).round() as usize];
        let (lo, hi) = (at(QUANTILES.0), at(QUANTILES.1));
        Ok(if hi > lo {
            (lo, hi)
        } else {
            (
                lo - 0.5 * lo.abs().max(1e-300),
                hi + 0.5 * hi.abs().max(1e-300),
            )
        })
    }

    /// Renders the map as an SVG document.
    ///
    /// # Errors
    /// A message when the grid and values disagree, nothing is finite, or drawing fails.
    pub fn to_svg(&self) -> Result<String, String> {
        let range = self.range()?;
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
            self.draw(&root, range)?;
        }
        Ok(svg)
    }

    /// Renders the map as a PNG image (8-bit RGB).
    ///
    /// # Errors
    /// A message when the grid and values disagree, nothing is finite, or drawing or
    /// encoding fails.
    pub fn to_png(&self) -> Result<Vec<u8>, String> {
        let range = self.range()?;
        let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
            self.draw(&root, range)?;
        }
        super::encode_png(&rgb, SIZE)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        (lo, hi): (f64, f64),
    ) -> Result<(), String> {
        register_font();
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        root.fill(&WHITE).map_err(err)?;
        let (map_area, bar_area) = root.split_horizontally(SIZE.0 - BAR);
        let half = |c: &[f64]| 0.5 * (c[1] - c[0]);
        let (hx, hy) = (half(self.xs), half(self.ys));
        let (x0, x1) = (self.xs[0] - hx, self.xs[self.xs.len() - 1] + hx);
        let (y0, y1) = (self.ys[0] - hy, self.ys[self.ys.len() - 1] + hy);
        let colour = |v: f64| {
            let t = ((v - lo) / (hi - lo)).clamp(0.0, 1.0) as f32;
            ViridisRGB::get_color(t)
        };
        let mut chart = ChartBuilder::on(&map_area)
            .margin(15)
            .margin_top(TITLE_SPACE)
            .x_label_area_size(55)
            .y_label_area_size(85)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&|v| tick_label(*v))
            .y_label_formatter(&|v| tick_label(*v))
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(err)?;
        let (xs, ys) = chart.plotting_area().get_pixel_range();
        let labels = Labels {
            title: self.title,
            x: self.x,
            y: self.y,
        };
        draw_labels(&map_area, &labels, (xs.clone(), ys.clone())).map_err(err)?;
        let nx = self.xs.len();
        let cells = self
            .values
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .map(|(k, &v)| {
                let (x, y) = (self.xs[k % nx], self.ys[k / nx]);
                Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], colour(v).filled())
            });
        chart.draw_series(cells).map_err(err)?;
        let mut legend = Vec::new();
        for (k, s) in self.overlays.iter().enumerate() {
            let line = if k == 0 {
                BLACK.to_rgba()
            } else {
                curve_colour(k - 1)
            };
            // A non-finite point breaks the curve; the legend names it once.
            let pieces = s
                .points
                .split(|p| !(p.0.is_finite() && p.1.is_finite()))
                .filter(|piece| piece.len() >= 2);
            for piece in pieces {
                chart
                    .draw_series(LineSeries::new(piece.iter().copied(), line.stroke_width(2)))
                    .map_err(err)?;
            }
            legend.push((s.label, LegendMark::Line(line, false)));
        }
        draw_legend(&map_area, &legend, (xs.start, ys.start), true).map_err(err)?;
        // The bar: tick labels on its left, its label close on its right, and a note at
        // an end whose values saturate (the scale spans the inner quantiles).
        let mut bar = ChartBuilder::on(&bar_area)
            .margin_top(TITLE_SPACE + 15)
            .margin_bottom(70)
            .margin_right(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(err)?;
        bar.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_labels(8)
            .y_label_formatter(&|v| tick_label(*v))
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(err)?;
        // Pixel ranges are the backend's; the bar area's own coordinates start at its base.
        let (bx, by) = bar.plotting_area().get_pixel_range();
        let (base_x, base_y) = bar_area.get_base_pixel();
        let (bx, by) = (
            bx.start - base_x..bx.end - base_x,
            by.start - base_y..by.end - base_y,
        );
        let (bw, _) = bar_area.dim_in_pixel();
        rich::draw(
            &bar_area,
            self.value,
            (bx.end + 16, (by.start + by.end) / 2),
            14.0,
            &BLACK,
            rich::Align::Centre,
            true,
        )
        .map_err(err)?;
        let beyond = |above: bool| {
            self.values
                .iter()
                .any(|&v| v.is_finite() && if above { v > hi } else { v < lo })
        };
        let short = |v: f64| tick_label(format!("{v:.3e}").parse().unwrap_or(v));
        for (above, y, text) in [
            (true, by.start - 22, format!("≥ {} saturate", short(hi))),
            (false, by.end + 8, format!("≤ {} saturate", short(lo))),
        ] {
            if beyond(above) {
                rich::draw(
                    &bar_area,
                    &text,
                    (bw as i32 / 2, y + 6),
                    10.0,
                    &BLACK,
                    rich::Align::Centre,
                    false,
                )
                .map_err(err)?;
            }
        }
        const STEPS: usize = 128;
        let dv = (hi - lo) / STEPS as f64;
        bar.draw_series((0..STEPS).map(|s| {
            let v = lo + dv * s as f64;
            Rectangle::new([(0.0, v), (1.0, v + dv)], colour(v + 0.5 * dv).filled())
        }))
        .map_err(err)?;
        root.present().map_err(err)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp<'a>(xs: &'a [f64], ys: &'a [f64], values: &'a [f64]) -> HeatMap<'a> {
        HeatMap {
            title: "ramp",
            x: "x (m)",
            y: "y (m)",
            value: "v (1)",
            xs,
            ys,
            values,
            overlays: &[],
        }
    }

    #[test]
    fn colour_range_spans_the_inner_quantiles() {
        let xs: Vec<f64> = (0..10).map(f64::from).collect();
        let ys: Vec<f64> = (0..10).map(f64::from).collect();
        let mut values: Vec<f64> = (0..100).map(f64::from).collect();
        values[99] = 1e9; // one outlier saturates instead of setting the scale
        values[0] = f64::NAN;
        let (lo, hi) = ramp(&xs, &ys, &values).range().expect("range");
        assert_eq!((lo, hi), (3.0, 97.0));
    }

    /// A map whose colour scale saturates says so at that end of the bar, and only there.
    #[test]
    fn saturated_ends_are_labelled() {
        let xs: Vec<f64> = (0..10).map(f64::from).collect();
        let mut values: Vec<f64> = (0..100).map(f64::from).collect();
        values[99] = 1e9;
        let svg = ramp(&xs, &xs, &values).to_svg().expect("svg");
        // The scale spans the 2 % and 98 % quantiles: 2 and 97 here.
        assert!(svg.contains("≥ 97 saturate"), "the top end is not labelled");
        assert!(
            svg.contains("≤ 2 saturate"),
            "the bottom end is not labelled"
        );
        let inside: Vec<f64> = (0..100).map(|v| f64::from(v % 2)).collect();
        let svg = ramp(&xs, &xs, &inside).to_svg().expect("svg");
        assert!(!svg.contains("saturate"), "nothing saturates here");
    }

    #[test]
    fn shape_mismatch_and_empty_fields_are_refused() {
        let xs = [0.0, 1.0];
        assert!(
            ramp(&xs, &xs, &[1.0; 3])
                .range()
                .expect_err("refused")
                .contains("3 values")
        );
        let nan = [f64::NAN; 4];
        assert!(
            ramp(&xs, &xs, &nan)
                .to_svg()
                .expect_err("refused")
                .contains("no finite")
        );
    }

    #[test]
    fn renders_svg_and_a_decodable_png() {
        let xs: Vec<f64> = (0..20).map(|i| 0.01 * f64::from(i)).collect();
        let ys: Vec<f64> = (0..8).map(|i| 0.01 * f64::from(i)).collect();
        let values: Vec<f64> = (0..160).map(|k| f64::from(k % 20)).collect();
        let line = [(0.05, 0.0), (0.1, 0.07)];
        let mut map = ramp(&xs, &ys, &values);
        let overlays = [Series {
            dashed_as: None,
            label: "centre",
            points: &line,
        }];
        map.overlays = &overlays;
        let svg = map.to_svg().expect("svg");
        assert!(svg.starts_with("<svg") && svg.contains("centre"));
        // 160 cells plus the 128 steps of the colour bar.
        assert!(svg.matches("<rect").count() >= 160 + 128);
        let png = map.to_png().expect("png");
        let decoder = png::Decoder::new(std::io::Cursor::new(png));
        let reader = decoder.read_info().expect("decodable");
        assert_eq!((reader.info().width, reader.info().height), SIZE);
    }
}
