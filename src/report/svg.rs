//! The report's figures as inline SVG (plotters' SVG backend, as `reproduce paper` draws its own):
//! a histogram of the engine's [`Histogram`], and box plots of [`BoxStats`]. The numbers are the
//! engine's; this only draws them.

use crate::analysis::Histogram;
use crate::comparison::BoxStats;
use crate::metrics::POS_THRESHOLDS_MM;
use plotters::coord::Shift;
use plotters::prelude::*;

const FONT: &str = "sans-serif";
const PANEL: (u32, u32) = (380, 250);
/// Nominal grey and calibrated blue (the paper study's palette).
pub const NOMINAL: RGBColor = RGBColor(127, 127, 127);
pub const CALIBRATED: RGBColor = RGBColor(31, 119, 180);

fn err(e: impl std::fmt::Display) -> String {
    format!("drawing: {e}")
}

/// The SVG element alone (no XML declaration), to be placed inside HTML.
fn inline(svg: String) -> String {
    match svg.find("<svg") {
        Some(k) => svg[k..].to_string(),
        None => svg,
    }
}

/// One histogram: the fraction of samples per bin in percent over `[lo, hi]`, with the paper's
/// ±0.3 mm and ±0.6 mm marks where they fall inside.
pub fn histogram(
    title: &str,
    x_desc: &str,
    h: &Histogram,
    colour: RGBColor,
) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PANEL).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let top = h.fractions.iter().fold(0.0f64, |m, &f| m.max(100.0 * f)) * 1.1;
        let top = if top > 0.0 { top } else { 1.0 };
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FONT, 13))
            .margin(6)
            .x_label_area_size(38)
            .y_label_area_size(44)
            .build_cartesian_2d(h.lo..h.hi, 0.0..top)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(5)
            .y_labels(5)
            .x_desc(x_desc)
            .y_desc("% of samples")
            .label_style((FONT, 10))
            .axis_desc_style((FONT, 11))
            .draw()
            .map_err(err)?;
        let marks = POS_THRESHOLDS_MM.iter().flat_map(|&t| [-t, t]);
        for m in marks.filter(|m| (h.lo..=h.hi).contains(m)) {
            chart
                .draw_series(LineSeries::new(
                    [(m, 0.0), (m, top)],
                    RGBColor(200, 200, 200).stroke_width(1),
                ))
                .map_err(err)?;
        }
        let width = h.bin_width();
        chart
            .draw_series(h.fractions.iter().enumerate().map(|(b, &f)| {
                let x0 = h.lo + b as f64 * width;
                Rectangle::new(
                    [(x0, 0.0), (x0 + width, 100.0 * f)],
                    colour.mix(0.85).filled(),
                )
            }))
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(inline(svg))
}

/// Box plots side by side: quartile box, median, Tukey whiskers, dots at the extremes.
pub fn box_plot(
    title: &str,
    y_desc: &str,
    boxes: &[(&str, Option<BoxStats>)],
    colour: RGBColor,
) -> Result<String, String> {
    let series: Vec<BoxSeries> = boxes
        .iter()
        .map(|(name, b)| BoxSeries {
            name: name.to_string(),
            colour,
            stats: b.as_ref(),
            legend: None,
        })
        .collect();
    let layout = BoxLayout {
        caption: title,
        y_desc,
        x_label_area: 30,
        y_label_area: 52,
        empty_range: (-1.0, 1.0),
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PANEL).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        box_chart(&root, &layout, &series)?;
        root.present().map_err(err)?;
    }
    Ok(inline(svg))
}

/// How a box-plot chart is laid out: its caption, the y axis's description, the label areas' sizes
/// (px), and the range of y shown when no box has data.
pub struct BoxLayout<'a> {
    pub caption: &'a str,
    pub y_desc: &'a str,
    pub x_label_area: u32,
    pub y_label_area: u32,
    pub empty_range: (f64, f64),
}

/// One box of a box-plot chart: its label under the axis, its colour, its statistics (none: an empty
/// slot) and its entry in the chart's legend, if it has one.
pub struct BoxSeries<'a> {
    pub name: String,
    pub colour: RGBColor,
    pub stats: Option<&'a BoxStats>,
    pub legend: Option<String>,
}

/// A chart of SVG box plots: quartile box, median, Tukey whiskers, dots at the extremes, side by side
/// on `area` (the report's panels, the paper study's figures). The chart is returned for a legend of
/// the boxes' [`BoxSeries::legend`]. Errors read `drawing: …`.
pub fn box_chart<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, Shift>,
    layout: &BoxLayout,
    boxes: &[BoxSeries],
) -> Result<Chart<'a, 'b>, String> {
    let (lo, hi) =
        BoxStats::padded_range(boxes.iter().filter_map(|b| b.stats)).unwrap_or(layout.empty_range);
    let n = boxes.len();
    let mut chart = ChartBuilder::on(area)
        .caption(layout.caption, (FONT, 13))
        .margin(6)
        .x_label_area_size(layout.x_label_area)
        .y_label_area_size(layout.y_label_area)
        .build_cartesian_2d(-0.5..(n as f64 - 0.5), lo..hi)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(n.max(1))
        .x_label_formatter(&|x| {
            let k = x.round();
            if (x - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < n {
                boxes[k as usize].name.clone()
            } else {
                String::new()
            }
        })
        .y_labels(6)
        .y_desc(layout.y_desc)
        .label_style((FONT, 10))
        .axis_desc_style((FONT, 11))
        .draw()
        .map_err(err)?;
    for (k, b) in boxes.iter().enumerate() {
        let Some(stats) = b.stats else { continue };
        draw_box(&mut chart, k as f64, stats, b.colour, b.legend.as_deref())?;
    }
    Ok(chart)
}

/// A chart of [`box_chart`]: SVG, both axes continuous.
pub type Chart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

fn draw_box(
    chart: &mut Chart<'_, '_>,
    x: f64,
    b: &BoxStats,
    c: RGBColor,
    legend: Option<&str>,
) -> Result<(), String> {
    let quartiles = chart
        .draw_series([Rectangle::new(
            [(x - 0.3, b.q1), (x + 0.3, b.q3)],
            c.mix(0.3).filled(),
        )])
        .map_err(err)?;
    if let Some(label) = legend {
        quartiles
            .label(label)
            .legend(move |(px, py)| Rectangle::new([(px, py - 4), (px + 10, py + 4)], c.filled()));
    }
    let style = c.stroke_width(2);
    for path in b.strokes(x) {
        chart
            .draw_series(LineSeries::new(path, style))
            .map_err(err)?;
    }
    chart
        .draw_series([b.min, b.max].map(|y| Circle::new((x, y), 2, c.filled())))
        .map_err(err)?;
    Ok(())
}
