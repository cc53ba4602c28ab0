//! The site's charts: horizontal bars with error bars, drawn with plotters as inline SVG (one
//! per ranking group and per task page).
//!
//! It draws what it is given ([`Bar`]s, in percent); it computes no figure and writes no file.

use super::model::Bar;

/// Bars with error bars, drawn with plotters (SVG).
pub(super) fn chart(bars: &[Bar]) -> String {
    use plotters::prelude::*;
    let mut svg = String::new();
    {
        let height = 70 + 36 * bars.len() as u32;
        let root = SVGBackend::with_string(&mut svg, (640, height)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let n = bars.len().max(1) as i32;
        if let Ok(mut c) = ChartBuilder::on(&root)
            .margin(10)
            .x_label_area_size(55)
            .y_label_area_size(200)
            .build_cartesian_2d(0f64..100f64, (0..n).into_segmented())
        {
            let labels: Vec<String> = bars.iter().map(|b| b.label.clone()).collect();
            let _ = c
                .configure_mesh()
                .disable_y_mesh()
                .x_labels(6)
                .x_label_formatter(&|v| format!("{v:.0}"))
                .label_style(("sans-serif", 20))
                .axis_desc_style(("sans-serif", 20))
                .x_desc("success, % (bars: 95% interval)")
                .y_label_formatter(&|v| match v {
                    SegmentValue::CenterOf(i) => {
                        labels.get(*i as usize).cloned().unwrap_or_default()
                    }
                    _ => String::new(),
                })
                .draw();
            let _ = c.draw_series(bars.iter().enumerate().map(|(i, b)| {
                Rectangle::new(
                    [
                        (0.0, SegmentValue::Exact(i as i32)),
                        (b.value, SegmentValue::Exact(i as i32 + 1)),
                    ],
                    RGBColor(70, 130, 180).filled(),
                )
            }));
            let _ = c.draw_series(bars.iter().enumerate().map(|(i, b)| {
                PathElement::new(
                    vec![
                        (b.low, SegmentValue::CenterOf(i as i32)),
                        (b.high, SegmentValue::CenterOf(i as i32)),
                    ],
                    BLACK.stroke_width(2),
                )
            }));
        }
        let _ = root.present();
    }
    svg
}
