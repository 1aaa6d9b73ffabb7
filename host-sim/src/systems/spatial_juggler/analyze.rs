//! `dexter analyze` on a spatial juggler scene: the apex-to-apex map linearized at its fixed
//! point, beside the closed forms (eq. 8, the lateral double integrator, eq. 21 for the
//! modified law) and the decay measured in simulation
//! ([`crate::model::spatial::analysis`]; `docs/spatial.md`).

use super::{SpatialConfig, SpatialJugglerSystem};
use crate::model::spatial::analysis::{self, SpatialAnalysis};
use crate::output::{json_text, JsonStyle};
use crate::scene::SceneFile;
use crate::system::{Analyzes, Failure, Report};
use serde::Serialize;
use std::fmt::Write as _;

/// The analysis of one scene.
#[derive(Serialize)]
struct SpatialReport {
    scene: String,
    law: crate::model::spatial::Law,
    /// The scene closes its loop through the fixed-rate controller: the map analyzed is the
    /// law's with perfect tracking, not the closed loop's (omitted from the JSON if not).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    perfect_tracking_of_a_closed_loop_scene: bool,
    #[serde(flatten)]
    analysis: SpatialAnalysis,
}

fn complex((re, im): (f64, f64)) -> String {
    format!(
        "{re:+.10} {} {:.10}i  (|lambda| {:.10})",
        if im < 0.0 { '-' } else { '+' },
        im.abs(),
        re.hypot(im)
    )
}

impl Report for SpatialReport {
    fn text(&self) -> String {
        let a = &self.analysis;
        let cf = &a.closed_forms;
        let mut o = format!(
            "spatial juggler scene {}: {} law, apex-to-apex map (b_x, b_y, b_z, b_x', b_y')\n",
            self.scene,
            self.law.name()
        );
        if self.perfect_tracking_of_a_closed_loop_scene {
            o += "  note:         the law's map with perfect tracking, not the closed loop of [spatial_juggler.sil] (its camera, estimator and joint tracking are not linearized)\n";
        }
        let fp: Vec<String> = a.fixed_point.iter().map(|x| format!("{x:.6}")).collect();
        let _ = writeln!(
            o,
            "  fixed point:  ({}), residual {:.2e}",
            fp.join(", "),
            a.fixed_point_residual
        );
        let _ = writeln!(
            o,
            "  eigenvalues:  (Jacobian error {:.1e}, uncertainty {:.1e})",
            a.jacobian_error, a.eigenvalue_tolerance
        );
        for e in &a.eigenvalues {
            let _ = writeln!(o, "    {}", complex((e.re, e.im)));
        }
        let _ = writeln!(o, "  closed forms:");
        let _ = writeln!(
            o,
            "    vertical, eq. 8's slope:   {}",
            complex((cf.vertical, 0.0))
        );
        for z in cf.lateral {
            let _ = writeln!(o, "    lateral:                   {}", complex(z));
        }
        for z in cf.radial_modified.into_iter().flatten() {
            let _ = writeln!(o, "    radial, eq. 21:            {}", complex(z));
        }
        let _ = writeln!(
            o,
            "    largest distance to the linearization: {:.2e}",
            a.closed_form_max_abs_diff
        );
        let m = &a.measured;
        let _ = writeln!(
            o,
            "  measured in simulation ({} bats from a small offset in each block):",
            analysis::FIT_BATS
        );
        let _ = writeln!(
            o,
            "    vertical:                  {}",
            complex((m.vertical, 0.0))
        );
        for z in m.radial {
            let _ = writeln!(o, "    radial:                    {}", complex(z));
        }
        for z in m.lateral {
            let _ = writeln!(o, "    lateral:                   {}", complex(z));
        }
        let _ = writeln!(
            o,
            "    spectral radius {:.6} against the linearization's {:.6} ({:.2e} relative)",
            m.spectral_radius(),
            a.eigenvalues.first().map_or(f64::NAN, |e| e.modulus),
            a.spectral_radius_rel_diff
        );
        let _ = writeln!(o, "  verdict:      {:?}", a.verdict);
        o
    }

    fn json(&self) -> Result<String, String> {
        json_text(self, JsonStyle::Compact)
    }
}

impl Analyzes for SpatialJugglerSystem {
    fn analyze<'a>(
        file: &'a SceneFile,
        cfg: &'a SpatialConfig,
    ) -> Result<Box<dyn Report + 'a>, Failure> {
        let analysis = analysis::analyze(&cfg.params, cfg.table.law)
            .map_err(|e| Failure::run(format!("{}: analyze: {e}", file.stem)))?;
        Ok(Box::new(SpatialReport {
            scene: cfg.name.clone(),
            law: cfg.table.law,
            perfect_tracking_of_a_closed_loop_scene: cfg.sil.is_some(),
            analysis,
        }))
    }
}
