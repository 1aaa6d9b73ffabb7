//! Draws one knob's trade-off figure, error against cost, from its CSV
//! ([`dexter_sim::plot::tradeoff`] describes the columns and the drawing).
//!
//! ```sh
//! cargo run --release -p dexter-sim --example tradeoff_figure -- data.csv out.svg "title"
//! ```
//!
//! `scripts/accuracy-figures.sh` measures the CSVs and runs this once per knob. A CSV that
//! does not parse is an error naming the file and the line (exit status 1); the SVG is
//! written whole or not at all.

use std::path::Path;
use std::process::ExitCode;

use dexter_sim::plot::tradeoff::csv_to_svg;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [csv, out, title] = args.as_slice() else {
        eprintln!("usage: tradeoff_figure DATA.csv OUT.svg TITLE");
        return ExitCode::from(2);
    };
    match csv_to_svg(Path::new(csv), Path::new(out), title) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("tradeoff_figure: {e}");
            ExitCode::FAILURE
        }
    }
}
