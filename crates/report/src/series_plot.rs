//! Lines over x, each with an optional uncertainty band: a per-axis error function with its
//! ± k·u band, residual RMS per cycle, a drift over time.

use plotters::prelude::*;

use crate::plot_style::{data, drawing, padded_range, palette, PlotError, SIZE};

/// One line: points (x, y) in drawing order and, optionally, the band (lower, upper) at each x.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub band: Option<Vec<(f64, f64)>>,
    /// Draw points as dots only (measurements) instead of a line (a model).
    pub markers: bool,
}

impl Series {
    pub fn new(name: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            band: None,
            markers: false,
        }
    }
    /// The band's lower and upper value at each point (same length as the points).
    pub fn band(mut self, band: Vec<(f64, f64)>) -> Self {
        self.band = Some(band);
        self
    }
    /// Dots instead of a line.
    pub fn markers(mut self) -> Self {
        self.markers = true;
        self
    }
}

/// A line plot with uncertainty bands.
#[derive(Debug, Clone, PartialEq)]
pub struct SeriesPlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

impl SeriesPlot {
    pub fn new(title: &str, x_label: &str, y_label: &str) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: vec![],
        }
    }
    pub fn series(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    fn check(&self) -> Result<(), PlotError> {
        if self.series.iter().all(|s| s.points.is_empty()) {
            return Err(data(&self.title, "no points to draw"));
        }
        for s in &self.series {
            if let Some(i) = s
                .points
                .iter()
                .position(|(x, y)| !(x.is_finite() && y.is_finite()))
            {
                return Err(data(
                    &self.title,
                    format!(
                        "series `{}`, point {i}: {:?} is not finite",
                        s.name, s.points[i]
                    ),
                ));
            }
            if let Some(b) = &s.band {
                if b.len() != s.points.len() {
                    return Err(data(
                        &self.title,
                        format!(
                            "series `{}`: {} band values for {} points",
                            s.name,
                            b.len(),
                            s.points.len()
                        ),
                    ));
                }
                if let Some(i) = b
                    .iter()
                    .position(|(lo, hi)| !(lo.is_finite() && hi.is_finite() && lo <= hi))
                {
                    return Err(data(
                        &self.title,
                        format!(
                            "series `{}`, band {i}: {:?} is not a finite [lower, upper]",
                            s.name, b[i]
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The plot as an SVG document.
    pub fn svg(&self) -> Result<String, PlotError> {
        self.check()?;
        let xs = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0));
        let ys = self.series.iter().flat_map(|s| {
            s.points
                .iter()
                .map(|p| p.1)
                .chain(s.band.iter().flatten().flat_map(|(a, b)| [*a, *b]))
        });
        let (x0, x1) = padded_range(xs).ok_or_else(|| data(&self.title, "no finite x"))?;
        let (y0, y1) = padded_range(ys).ok_or_else(|| data(&self.title, "no finite y"))?;
        let mut out = String::new();
        {
            let root = SVGBackend::with_string(&mut out, SIZE).into_drawing_area();
            root.fill(&WHITE).map_err(|e| drawing(&self.title, e))?;
            let mut chart = ChartBuilder::on(&root)
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
            for (i, s) in self.series.iter().enumerate() {
                let colour = palette(i);
                if let Some(band) = &s.band {
                    // the band as one polygon: upper edge forwards, lower edge back
                    let mut outline: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .zip(band)
                        .map(|((x, _), (_, hi))| (*x, *hi))
                        .collect();
                    outline.extend(
                        s.points
                            .iter()
                            .zip(band)
                            .rev()
                            .map(|((x, _), (lo, _))| (*x, *lo)),
                    );
                    chart
                        .draw_series(std::iter::once(Polygon::new(
                            outline,
                            colour.mix(0.2).filled(),
                        )))
                        .map_err(|e| drawing(&self.title, e))?;
                }
                let drawn = if s.markers {
                    chart
                        .draw_series(s.points.iter().map(|p| Circle::new(*p, 3, colour.filled())))
                        .map_err(|e| drawing(&self.title, e))?
                } else {
                    chart
                        .draw_series(LineSeries::new(
                            s.points.iter().copied(),
                            colour.stroke_width(2),
                        ))
                        .map_err(|e| drawing(&self.title, e))?
                };
                drawn.label(&s.name).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            }
            if self.series.len() > 1 || self.series.iter().any(|s| s.band.is_some()) {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK.mix(0.4))
                    .draw()
                    .map_err(|e| drawing(&self.title, e))?;
            }
            root.present().map_err(|e| drawing(&self.title, e))?;
        }
        Ok(out)
    }
}
