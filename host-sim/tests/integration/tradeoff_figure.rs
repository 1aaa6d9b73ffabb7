//! The trade-off figures' CSV reader and renderer (`dexter_sim::plot::tradeoff`,
//! `examples/tradeoff_figure.rs`): a bad CSV is an error naming its line, never a figure
//! with a point dropped; a good one gives an SVG with every label and both axis titles.

use dexter_sim::plot::tradeoff::{best_trades, csv_to_svg, parse_csv, svg, Axis, CsvError, HEADER};

fn csv(rows: &[&str]) -> String {
    let mut text = format!("{HEADER}\n");
    for r in rows {
        text.push_str(r);
        text.push('\n');
    }
    text
}

const GOOD: [&str; 4] = [
    "drag 0,exact events,8.3,µs per 200 impacts,0,worst landing-speed relative error",
    "drag 0,RK4 step 1e-3 s,4267,µs per 200 impacts,1.6e-15,worst landing-speed relative error",
    "drag 0.1 1/m,RK45 tol 1e-9 m,736,µs per 200 impacts,1.3e-9,worst landing-speed relative error",
    "drag 0.1 1/m,RK4 step 1e-2 s,522,µs per 200 impacts,6.0e-10,worst landing-speed relative error",
];

#[test]
fn a_good_csv_is_read_whole() {
    let fig = parse_csv(&csv(&GOOD)).unwrap();
    assert_eq!(fig.cost_unit, "µs per 200 impacts");
    assert_eq!(fig.error_unit, "worst landing-speed relative error");
    assert_eq!(fig.points.len(), 4);
    assert_eq!(fig.points[1].series, "drag 0");
    assert_eq!(fig.points[1].label, "RK4 step 1e-3 s");
    assert_eq!(fig.points[1].cost, 4267.0);
    assert_eq!(fig.points[1].error, 1.6e-15);
}

#[test]
fn a_line_with_a_missing_field_is_named() {
    let mut rows = GOOD.to_vec();
    rows[1] = "drag 0,RK4 step 1e-3 s,4267,µs per 200 impacts,1.6e-15";
    let e = parse_csv(&csv(&rows)).unwrap_err();
    assert_eq!(e, CsvError::Fields { line: 3, found: 5 });
    let msg = e.to_string();
    assert!(
        msg.starts_with("line 3: expected 6 comma-separated fields"),
        "{msg}"
    );
    assert!(msg.contains("found 5"), "{msg}");
}

#[test]
fn a_label_with_a_comma_is_a_field_too_many() {
    let rows = ["s,RK4, 1 ms,1,cost,1e-3,error"];
    let e = parse_csv(&csv(&rows)).unwrap_err();
    assert_eq!(e, CsvError::Fields { line: 2, found: 7 });
}

#[test]
fn a_bad_number_names_its_line_and_column() {
    for (row, column, text) in [
        ("s,a,fast,cost,1e-3,error", "cost", "fast"),
        ("s,a,0,cost,1e-3,error", "cost", "0"),
        ("s,a,-3,cost,1e-3,error", "cost", "-3"),
        ("s,a,inf,cost,1e-3,error", "cost", "inf"),
        ("s,a,3,cost,NaN,error", "error", "NaN"),
        ("s,a,3,cost,-1e-9,error", "error", "-1e-9"),
    ] {
        let rows = [GOOD[0], GOOD[1], row];
        let e = parse_csv(&csv(&rows)).unwrap_err();
        match &e {
            CsvError::Number {
                line,
                column: c,
                text: t,
                ..
            } => {
                assert_eq!((*line, *c, t.as_str()), (4, column, text), "{row}");
            }
            other => panic!("{row}: {other:?}"),
        }
        assert!(
            e.to_string()
                .starts_with(&format!("line 4: {column} {text:?} is not")),
            "{e}"
        );
    }
}

#[test]
fn an_empty_field_is_named() {
    let e = parse_csv(&csv(&["s,,3,cost,1e-3,error"])).unwrap_err();
    assert_eq!(
        e,
        CsvError::Empty {
            line: 2,
            column: "label"
        }
    );
    assert_eq!(e.to_string(), "line 2: label is empty");
}

#[test]
fn units_must_agree_down_the_file() {
    let rows = [
        GOOD[0],
        "drag 0,RK4,4267,ms per 200 impacts,1.6e-15,worst landing-speed relative error",
    ];
    let e = parse_csv(&csv(&rows)).unwrap_err();
    assert!(
        matches!(
            e,
            CsvError::Unit {
                line: 3,
                column: "cost_unit",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with("line 3: cost_unit \"ms per 200 impacts\" differs"),
        "{e}"
    );
}

#[test]
fn the_header_must_be_there_and_points_after_it() {
    let e = parse_csv("label,cost,error\nsin,1,2\n").unwrap_err();
    assert!(
        e.to_string().starts_with("line 1: expected the header"),
        "{e}"
    );
    assert!(parse_csv("")
        .unwrap_err()
        .to_string()
        .starts_with("line 1: the file is empty"));
    assert_eq!(parse_csv(&csv(&[])).unwrap_err(), CsvError::NoPoints);
}

#[test]
fn the_svg_carries_every_label_and_both_axis_titles() {
    let fig = parse_csv(&csv(&GOOD)).unwrap();
    let doc = svg(&fig, "Flight: exact events against RK4 and RK45").unwrap();
    assert!(doc.starts_with("<svg"), "{}", &doc[..80.min(doc.len())]);
    for text in [
        "Flight: exact events against RK4 and RK45",
        "exact events (error 0)", // a zero error on a log axis says so
        "RK4 step 1e-3 s",
        "RK45 tol 1e-9 m",
        "RK4 step 1e-2 s",
        "drag 0.1 1/m",
        "µs per 200 impacts",
        "worst landing-speed relative error",
        "triangle on the floor: error exactly 0",
    ] {
        assert!(doc.contains(text), "the SVG lacks {text:?}");
    }
}

#[test]
fn a_linear_error_axis_places_zero_as_it_is() {
    let rows = [
        "map,f32,9,instructions,2.4e-8,relative error",
        "map,f64,9,instructions,0,relative error",
    ];
    let fig = parse_csv(&csv(&rows)).unwrap();
    let doc = svg(&fig, "Precision").unwrap();
    // plotters writes a text element's content on a line of its own
    assert!(doc.contains("\nf64\n"), "no f64 label");
    assert!(!doc.contains("(error 0)"), "a linear axis has room for 0");
    assert!(!doc.contains("triangle on the floor"));
}

#[test]
fn axes_turn_logarithmic_at_a_decade() {
    assert!(matches!(
        Axis::for_values(&[1.0, 9.0]).unwrap(),
        Axis::Linear(..)
    ));
    assert!(matches!(
        Axis::for_values(&[1.0, 10.0]).unwrap(),
        Axis::Log(..)
    ));
    match Axis::for_values(&[0.0, 1e-15, 1e-9]).unwrap() {
        Axis::Log(lo, hi) => assert!(lo < 1e-15 && hi > 1e-9, "{lo} {hi}"),
        other => panic!("{other:?}"),
    }
    // one positive value and a zero: no decade to span, so linear through 0
    assert!(matches!(
        Axis::for_values(&[0.0, 2.4e-8]).unwrap(),
        Axis::Linear(..)
    ));
}

#[test]
fn the_best_trades_are_the_undominated_points() {
    let fig = parse_csv(&csv(&GOOD)).unwrap();
    let best: Vec<&str> = best_trades(&fig.points)
        .iter()
        .map(|p| p.label.as_str())
        .collect();
    assert_eq!(best, ["exact events"]);
    let drag: Vec<_> = fig.points[2..].to_vec();
    let best: Vec<&str> = best_trades(&drag)
        .iter()
        .map(|p| p.label.as_str())
        .collect();
    // RK4 1e-2 is cheaper and more accurate than RK45 1e-9 here
    assert_eq!(best, ["RK4 step 1e-2 s"]);
}

#[test]
fn the_file_form_names_the_file_and_line_and_writes_nothing_on_error() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.csv");
    let out = dir.path().join("bad.svg");
    std::fs::write(&bad, csv(&[GOOD[0], "s,a,3,cost"])).unwrap();
    let e = csv_to_svg(&bad, &out, "t").unwrap_err();
    assert!(e.contains("bad.csv: line 3: expected 6"), "{e}");
    assert!(!out.exists());
    let good = dir.path().join("good.csv");
    let out = dir.path().join("good.svg");
    std::fs::write(&good, csv(&GOOD)).unwrap();
    csv_to_svg(&good, &out, "t").unwrap();
    assert!(std::fs::read_to_string(&out)
        .unwrap()
        .contains("RK45 tol 1e-9 m"));
}
