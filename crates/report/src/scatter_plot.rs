//! Points coloured by a value (viridis, with a colour bar): residuals over the workspace,
//! errors over two axes, a residual against a term's signal.

use plotters::prelude::*;

use crate::plot_style::{data, drawing, padded_range, viridis, PlotError, SIZE};

/// A scatter plot of (x, y) points, each coloured by its value.
#[derive(Debug, Clone, PartialEq)]
pub struct ScatterPlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// What the colour shows (with its unit), written beside the colour bar.
    pub value_label: String,
    pub points: Vec<(f64, f64, f64)>,
}

/// Ticks written on the colour bar.
const BAR_TICKS: usize = 5;

impl ScatterPlot {
    pub fn new(
        title: &str,
        x_label: &str,
        y_label: &str,
        value_label: &str,
        points: Vec<(f64, f64, f64)>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            value_label: value_label.into(),
            points,
        }
    }

    /// The plot as an SVG document: one circle per point, and a colour bar of [`BAR_TICKS`]
    /// labelled steps.
    pub fn svg(&self) -> Result<String, PlotError> {
        if self.points.is_empty() {
            return Err(data(&self.title, "no points to draw"));
        }
        if let Some(i) = self
            .points
            .iter()
            .position(|(x, y, v)| !(x.is_finite() && y.is_finite() && v.is_finite()))
        {
            return Err(data(
                &self.title,
                format!("point {i}: {:?} is not finite", self.points[i]),
            ));
        }
        let (x0, x1) = padded_range(self.points.iter().map(|p| p.0))
            .ok_or_else(|| data(&self.title, "no finite x"))?;
        let (y0, y1) = padded_range(self.points.iter().map(|p| p.1))
            .ok_or_else(|| data(&self.title, "no finite y"))?;
        let (v0, v1) = self
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.2), b.max(p.2))
            });
        let span = if v1 > v0 { v1 - v0 } else { 1.0 };
        let mut out = String::new();
        {
            let root = SVGBackend::with_string(&mut out, SIZE).into_drawing_area();
            root.fill(&WHITE).map_err(|e| drawing(&self.title, e))?;
            let (main, bar) = root.split_horizontally(SIZE.0 - 110);
            let mut chart = ChartBuilder::on(&main)
                .caption(&self.title, ("sans-serif", 18))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(64)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| drawing(&self.title, e))?;
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(|e| drawing(&self.title, e))?;
            chart
                .draw_series(
                    self.points.iter().map(|(x, y, v)| {
                        Circle::new((*x, *y), 4, viridis((v - v0) / span).filled())
                    }),
                )
                .map_err(|e| drawing(&self.title, e))?;
            // colour bar: BAR_TICKS steps, lowest at the bottom
            let bar = bar.margin(40, 40, 10, 10);
            let (w, h) = bar.dim_in_pixel();
            let step = h as i32 / BAR_TICKS as i32;
            for k in 0..BAR_TICKS {
                let t = k as f64 / (BAR_TICKS - 1) as f64;
                let top = h as i32 - (k as i32 + 1) * step;
                bar.draw(&Rectangle::new(
                    [(0, top), (18, top + step)],
                    viridis(t).filled(),
                ))
                .map_err(|e| drawing(&self.title, e))?;
                bar.draw(&Text::new(
                    format!("{:.3}", v0 + t * (v1 - v0)),
                    (22, top + step / 2 - 6),
                    ("sans-serif", 12),
                ))
                .map_err(|e| drawing(&self.title, e))?;
            }
            let _ = w;
            bar.draw(&Text::new(
                self.value_label.clone(),
                (0, -20),
                ("sans-serif", 12),
            ))
            .map_err(|e| drawing(&self.title, e))?;
            root.present().map_err(|e| drawing(&self.title, e))?;
        }
        Ok(out)
    }
}
