//! The report's plots are well-formed SVG with exactly the data drawn (points, bands, bars),
//! bad data is refused with the series and point named, and the HTML holds the tables,
//! escaped text and figures, written with one SVG file per figure.

use metrocell_report::{HistogramPlot, PlotError, Report, ScatterPlot, Series, SeriesPlot, Table};
use quick_xml::events::Event;
use quick_xml::Reader;

/// Every element of an SVG document: name and attributes (the parse fails on malformed XML).
fn elements(svg: &str) -> Vec<(String, Vec<(String, String)>)> {
    let mut r = Reader::from_str(svg);
    let mut out = Vec::new();
    loop {
        match r
            .read_event()
            .unwrap_or_else(|e| panic!("SVG does not parse: {e}\n{svg}"))
        {
            Event::Start(e) | Event::Empty(e) => {
                let name = String::from_utf8(e.name().as_ref().to_vec()).unwrap();
                let attrs = e
                    .attributes()
                    .map(|a| a.unwrap())
                    .map(|a| {
                        (
                            String::from_utf8(a.key.as_ref().to_vec()).unwrap(),
                            a.unescape_value().unwrap().to_string(),
                        )
                    })
                    .collect();
                out.push((name, attrs));
            }
            Event::Eof => break,
            _ => {}
        }
    }
    assert_eq!(out.first().map(|e| e.0.as_str()), Some("svg"));
    out
}

fn attr<'a>(e: &'a (String, Vec<(String, String)>), key: &str) -> Option<&'a str> {
    e.1.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

fn with<'a>(
    els: &'a [(String, Vec<(String, String)>)],
    name: &str,
    pairs: &[(&str, &str)],
) -> Vec<&'a (String, Vec<(String, String)>)> {
    els.iter()
        .filter(|e| e.0 == name && pairs.iter().all(|(k, v)| attr(e, k) == Some(v)))
        .collect()
}

fn point_count(e: &(String, Vec<(String, String)>)) -> usize {
    attr(e, "points").unwrap().split_whitespace().count()
}

#[test]
fn a_series_with_a_band_draws_one_line_and_one_band_of_its_points() {
    let n = 25;
    let pts: Vec<(f64, f64)> = (0..n)
        .map(|i| (i as f64 * 10.0, (i as f64 / 4.0).sin() * 5.0))
        .collect();
    let band: Vec<(f64, f64)> = pts.iter().map(|(_, y)| (y - 1.0, y + 1.0)).collect();
    let svg = SeriesPlot::new("X error ± 2u", "x [mm]", "e [µm]")
        .series(Series::new("fitted", pts.clone()).band(band))
        .series(Series::new("measured", pts.iter().map(|(x, y)| (*x, y + 0.3)).collect()).markers())
        .svg()
        .unwrap();
    let els = elements(&svg);
    let bands = with(&els, "polygon", &[("fill", "#0072B2"), ("opacity", "0.2")]);
    assert_eq!(bands.len(), 1);
    assert_eq!(
        point_count(bands[0]),
        2 * n,
        "band outline: upper and lower edge"
    );
    let lines: Vec<_> = with(
        &els,
        "polyline",
        &[("stroke", "#0072B2"), ("stroke-width", "2")],
    )
    .into_iter()
    .filter(|e| point_count(e) == n)
    .collect();
    assert_eq!(lines.len(), 1, "one data line of {n} points");
    assert_eq!(
        with(&els, "circle", &[("fill", "#D55E00")]).len(),
        n,
        "one dot per measured point"
    );
    assert!(svg.contains("x [mm]") && svg.contains("e [µm]") && svg.contains("X error ± 2u"));
}

#[test]
fn a_scatter_draws_one_circle_per_point_coloured_by_value() {
    let pts: Vec<(f64, f64, f64)> = (0..40)
        .map(|i| {
            (
                (i % 8) as f64 * 100.0,
                (i / 8) as f64 * 100.0,
                i as f64 * 0.5 - 3.0,
            )
        })
        .collect();
    let svg = ScatterPlot::new(
        "residual over the workspace",
        "x [mm]",
        "y [mm]",
        "residual [µm]",
        pts,
    )
    .svg()
    .unwrap();
    let els = elements(&svg);
    let circles = with(&els, "circle", &[]);
    assert_eq!(circles.len(), 40);
    // lowest value → viridis start, highest → viridis end
    assert_eq!(attr(circles[0], "fill"), Some("#440154"));
    assert_eq!(attr(circles[39], "fill"), Some("#FDE725"));
    assert!(
        svg.contains("residual [µm]") && svg.contains("-3.000") && svg.contains("16.500"),
        "colour bar labels"
    );
}

#[test]
fn histograms_count_on_shared_bins_and_draw_a_bar_per_non_empty_bin() {
    let before: Vec<f64> = (0..200)
        .map(|i| ((i * 37) % 101) as f64 / 10.0 - 5.0)
        .collect();
    let after: Vec<f64> = (0..200)
        .map(|i| ((i * 37) % 101) as f64 / 50.0 - 1.0)
        .collect();
    let h = HistogramPlot::new("residuals", "residual [µm]", 20)
        .sample("before", before.clone())
        .sample("after", after.clone());
    let (edges, counts) = h.counts().unwrap();
    assert_eq!(edges.len(), 21);
    assert_eq!(counts[0].iter().sum::<usize>(), 200);
    assert_eq!(counts[1].iter().sum::<usize>(), 200);
    for (k, c) in counts[1].iter().enumerate() {
        assert_eq!(
            *c,
            after
                .iter()
                .filter(|x| **x >= edges[k] && (**x < edges[k + 1] || k == 19))
                .count(),
            "bin {k}"
        );
    }
    let non_empty: usize = counts.iter().flatten().filter(|c| **c > 0).count();
    let els = elements(&h.svg().unwrap());
    let bars = with(&els, "rect", &[("opacity", "0.45")]);
    assert_eq!(bars.len(), non_empty + 2, "bars plus two legend keys");
}

#[test]
fn bad_data_is_refused_with_the_point_named() {
    let e = SeriesPlot::new("p", "x", "y")
        .series(Series::new("s", vec![(0.0, 1.0), (1.0, f64::NAN)]))
        .svg()
        .unwrap_err();
    assert!(
        matches!(&e, PlotError::Data { .. }) && e.to_string().contains("series `s`, point 1"),
        "{e}"
    );
    let e = SeriesPlot::new("p", "x", "y")
        .series(Series::new("s", vec![(0.0, 1.0)]).band(vec![]))
        .svg()
        .unwrap_err();
    assert!(e.to_string().contains("0 band values for 1 points"), "{e}");
    assert!(SeriesPlot::new("p", "x", "y")
        .svg()
        .unwrap_err()
        .to_string()
        .contains("no points"));
    assert!(
        ScatterPlot::new("s", "x", "y", "v", vec![(0.0, 0.0, f64::INFINITY)])
            .svg()
            .unwrap_err()
            .to_string()
            .contains("point 0")
    );
    assert!(HistogramPlot::new("h", "x", 5)
        .sample("a", vec![1.0, f64::NAN])
        .svg()
        .unwrap_err()
        .to_string()
        .contains("sample `a`, value 1"));
}

#[test]
fn the_html_holds_the_tables_escaped_text_and_figures() {
    let mut r = Report::new("Calibration <xfyz>");
    let svg = SeriesPlot::new("e", "x", "y")
        .series(Series::new("a", vec![(0.0, 0.0), (1.0, 1.0)]))
        .svg()
        .unwrap();
    r.section("Summary")
        .paragraph("RMS 31.2 µm → 4.1 µm; a < b & c")
        .preformatted("metrocell calibrate --model m.yaml bag");
    let mut t = Table::new(&["parameter", "value", "u"]).caption("fitted");
    for i in 0..7 {
        t.push(vec![
            format!("positioning[x].c{i}"),
            format!("{:.2} µm", i as f64 * 1.5),
            "0.21 µm".into(),
        ]);
    }
    r.section("Parameters")
        .table(t)
        .figure("ex", "X error", svg);
    let html = r.to_html();
    assert_eq!(html.matches("<tr>").count(), 8, "header + 7 rows");
    assert_eq!(
        html.matches("<td class=\"n\">").count(),
        14,
        "numbers right-aligned"
    );
    assert!(
        html.contains("<title>Calibration &lt;xfyz&gt;</title>")
            && html.contains("a &lt; b &amp; c")
    );
    assert_eq!(html.matches("<svg").count(), 1);
    assert!(!html.contains("<?xml"));
    let dir = std::env::temp_dir().join(format!("metrocell_report_test_{}", std::process::id()));
    let page = r.write_to(&dir).unwrap();
    assert_eq!(std::fs::read_to_string(&page).unwrap(), html);
    let file = std::fs::read_to_string(dir.join("figures/ex.svg")).unwrap();
    elements(&file);
    std::fs::remove_dir_all(&dir).unwrap();
}
