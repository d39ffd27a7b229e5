//! Overlaid histograms on shared bins: residuals before and after a fit, or two channels.

use plotters::prelude::*;

use crate::plot_style::{data, drawing, padded_range, palette, PlotError, SIZE};

/// Histograms of several samples on the same bins, drawn translucent over each other.
#[derive(Debug, Clone, PartialEq)]
pub struct HistogramPlot {
    pub title: String,
    pub x_label: String,
    pub bins: usize,
    /// (name, values) per sample.
    pub samples: Vec<(String, Vec<f64>)>,
}

impl HistogramPlot {
    pub fn new(title: &str, x_label: &str, bins: usize) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            bins: bins.max(1),
            samples: vec![],
        }
    }
    pub fn sample(mut self, name: &str, values: Vec<f64>) -> Self {
        self.samples.push((name.into(), values));
        self
    }

    /// Bin edges (bins + 1) over all samples, and each sample's counts.
    pub fn counts(&self) -> Result<(Vec<f64>, Vec<Vec<usize>>), PlotError> {
        if self.samples.iter().all(|(_, v)| v.is_empty()) {
            return Err(data(&self.title, "no values to count"));
        }
        for (name, v) in &self.samples {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(data(
                    &self.title,
                    format!("sample `{name}`, value {i} is not finite ({})", v[i]),
                ));
            }
        }
        let (lo, hi) = padded_range(self.samples.iter().flat_map(|(_, v)| v.iter().copied()))
            .ok_or_else(|| data(&self.title, "no finite values"))?;
        let width = (hi - lo) / self.bins as f64;
        let edges: Vec<f64> = (0..=self.bins).map(|k| lo + k as f64 * width).collect();
        let counts = self
            .samples
            .iter()
            .map(|(_, v)| {
                let mut c = vec![0; self.bins];
                for x in v {
                    c[(((x - lo) / width) as usize).min(self.bins - 1)] += 1;
                }
                c
            })
            .collect();
        Ok((edges, counts))
    }

    /// The plot as an SVG document: one rectangle per non-empty bin and sample.
    pub fn svg(&self) -> Result<String, PlotError> {
        let (edges, counts) = self.counts()?;
        let top = counts.iter().flatten().copied().max().unwrap_or(1).max(1) as f64 * 1.08;
        let mut out = String::new();
        {
            let root = SVGBackend::with_string(&mut out, SIZE).into_drawing_area();
            root.fill(&WHITE).map_err(|e| drawing(&self.title, e))?;
            let mut chart = ChartBuilder::on(&root)
                .caption(&self.title, ("sans-serif", 18))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(56)
                .build_cartesian_2d(edges[0]..edges[self.bins], 0.0..top)
                .map_err(|e| drawing(&self.title, e))?;
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc("count")
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(|e| drawing(&self.title, e))?;
            for (i, ((name, _), c)) in self.samples.iter().zip(&counts).enumerate() {
                let colour = palette(i);
                let bars = c.iter().enumerate().filter(|(_, n)| **n > 0).map(|(k, n)| {
                    Rectangle::new(
                        [(edges[k], 0.0), (edges[k + 1], *n as f64)],
                        colour.mix(0.45).filled(),
                    )
                });
                chart
                    .draw_series(bars)
                    .map_err(|e| drawing(&self.title, e))?
                    .label(format!("{name} (n = {})", c.iter().sum::<usize>()))
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.mix(0.45).filled())
                    });
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.4))
                .draw()
                .map_err(|e| drawing(&self.title, e))?;
            root.present().map_err(|e| drawing(&self.title, e))?;
        }
        Ok(out)
    }
}
