//! # metrocell-report — HTML reports with plots
//!
//! What `metrocell calibrate`, `diagnose` and the demo write for a person to read: a single HTML
//! page of sections with paragraphs, tables and figures, and the figures themselves as SVG
//! files beside it. Plots are drawn with the `plotters` crate (SVG backend), never by hand:
//!
//! * [`SeriesPlot`] — lines over x, each with an optional uncertainty band (e.g. a per-axis
//!   error function ± k·u);
//! * [`ScatterPlot`] — points coloured by a value on a viridis scale with a colour bar (e.g.
//!   residuals over the workspace);
//! * [`HistogramPlot`] — overlaid histograms on shared bins (e.g. residuals before/after).
//!
//! Units are the caller's: reports show mm and µm (metrocell's convention), so callers convert
//! from SI before plotting. SVG text is laid out by plotters' built-in estimate and drawn by the
//! viewer's font, so nothing here needs a font file. (A crate that turns on plotters' `ttf`
//! feature elsewhere in the workspace would switch that for font-kit, which needs fontconfig:
//! draw through this crate instead.) PNG is not written: every viewer the reports target
//! (browsers, Foxglove) shows SVG.
//!
//! ```no_run
//! use metrocell_report::{Report, SeriesPlot, Series, Table};
//! let plot = SeriesPlot::new("X positioning error", "x [mm]", "e_x [µm]")
//!     .series(Series::new("fitted", vec![(0.0, 0.0), (400.0, 4.1), (800.0, 7.9)]).band(vec![(-0.5, 0.5), (3.5, 4.7), (7.1, 8.7)]));
//! let mut r = Report::new("Calibration of xfyz_shift");
//! r.section("Error functions").paragraph("Bands are ± 2u (k = 2).").figure("ex", "X positioning", plot.svg().unwrap());
//! r.section("Parameters").table(Table::new(&["parameter", "value", "u"]).row(vec!["positioning[x].c1".into(), "11.9 µm".into(), "0.2 µm".into()]));
//! r.write_to(std::path::Path::new("report")).unwrap();
//! ```

mod histogram_plot;
mod html;
mod plot_style;
mod scatter_plot;
mod series_plot;

pub use histogram_plot::HistogramPlot;
pub use html::{Block, Figure, Report, Section, Table};
pub use plot_style::PlotError;
pub use scatter_plot::ScatterPlot;
pub use series_plot::{Series, SeriesPlot};
