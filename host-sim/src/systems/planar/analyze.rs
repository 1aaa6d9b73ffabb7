//! `dexter analyze` on a planar scene: the impact-to-impact map linearized at its fixed
//! point, beside the closed forms (eq. 11, 16, 26; `docs/planar.md`).

use super::PlanarConfig;
use crate::model::planar::analysis::{self, AnalysisReport};
use crate::model::planar::{Body, PlanarModel};
use crate::scene::SceneFile;
use crate::system::{Failure, Report};
use std::fmt::Write as _;

/// The label of each closed-form eigenvalue (same order as `ClosedForms::predicted`).
fn closed_form_labels(model: &PlanarModel) -> [&'static str; 4] {
    match model.body {
        Body::PointMass => [
            "eq. 3: 1 - 2 kappa",
            "energy: 1 - (1+e) kappa_E y*^2",
            "",
            "",
        ],
        Body::Rigid { .. } => [
            "x' (horizontal drift): 1",
            "energy: 1 - (1+e) kappa_E y*^2",
            "eq. 11",
            "eq. 11",
        ],
    }
}

/// For each numerical eigenvalue, the index of the closed form matched to it (greedy by
/// distance, one to one, as `analysis::analyze` does).
fn match_closed_forms(r: &AnalysisReport) -> Vec<Option<usize>> {
    let pred = &r.closed_form.predicted[..r.closed_form.count];
    let mut out = vec![None; r.eigenvalues.len()];
    for (i, p) in pred.iter().enumerate() {
        let best = r
            .eigenvalues
            .iter()
            .enumerate()
            .filter(|(k, _)| out[*k].is_none())
            .map(|(k, q)| (k, (q.re - p.0).hypot(q.im - p.1)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, _)) = best {
            out[k] = Some(i);
        }
    }
    out
}

fn complex(re: f64, im: f64) -> String {
    format!(
        "{re:+.10} {} {:.10}i",
        if im < 0.0 { '-' } else { '+' },
        im.abs()
    )
}

fn regime(r: &AnalysisReport) -> String {
    let k = r.params.kappa;
    let kc = r.closed_form.kappa_crit_eq16;
    if kc.is_nan() {
        return if k > 0.0 && k < 1.0 {
            "0 < kappa < 1: the point-mass angle converges (eq. 4)".into()
        } else {
            "kappa outside (0, 1): the point-mass angle does not converge (eq. 4)".into()
        };
    }
    if k < 1.0 {
        "kappa < 1: real pair, one outside the unit circle (eq. 13)".into()
    } else if k == 1.0 {
        "kappa = 1: double eigenvalue 1".into()
    } else if k < kc {
        "1 < kappa < kappa_crit: complex pair on the unit circle (eq. 14)".into()
    } else if k == kc {
        "kappa = kappa_crit: double eigenvalue -1".into()
    } else {
        "kappa > kappa_crit: real pair, one below -1 (eq. 15)".into()
    }
}

/// Each numerical eigenvalue beside the closed form matched to it.
fn eigenvalue_table(r: &AnalysisReport, model: &PlanarModel) -> String {
    let mut o = format!(
        "  eigenvalues   {:<36} {:>13}   {:<36} which\n",
        "numerical (re + im i)", "|lambda|", "closed form"
    );
    let labels = closed_form_labels(model);
    for (ev, m) in r.eigenvalues.iter().zip(match_closed_forms(r)) {
        let (cf, which) = match m {
            Some(i) => {
                let (re, im) = r.closed_form.predicted[i];
                (complex(re, im), labels[i])
            }
            None => ("-".to_string(), ""),
        };
        let _ = writeln!(
            o,
            "                {:<36} {:>13.10}   {:<36} {which}",
            complex(ev.re, ev.im),
            ev.modulus,
            cf
        );
    }
    o
}

fn analyze_text(name: &str, r: &AnalysisReport, model: &PlanarModel) -> String {
    let p = &r.params;
    let c = &r.closed_form;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "planar scene {name}: the impact-to-impact map linearized at its fixed point"
    );
    let _ = writeln!(
        o,
        "  parameters:   rho {} m, l {} m, G {} m/s^2, e {}, kappa {}, kappa_E {} s^2/m^2",
        p.rho_m, p.l_m, p.gravity_mps2, p.restitution, p.kappa, p.kappa_e_s2pm2
    );
    let coords = if r.fixed_point.len() == 2 {
        "(x', y')"
    } else {
        "(rho theta, x', y', rho theta')"
    };
    let fp: Vec<String> = r.fixed_point.iter().map(|v| format!("{v:.6}")).collect();
    let _ = writeln!(
        o,
        "  fixed point:  eta* {:.6} J/kg, impact velocity y* {:.6} m/s; z* = {coords} = ({}), residual {:.1e}",
        p.target_energy_jpkg,
        p.impact_velocity_mps,
        fp.join(", "),
        r.fixed_point_residual
    );
    let _ = writeln!(
        o,
        "  Jacobian:     central differences, Richardson, steps chosen per column; error estimate {:.1e}",
        r.jacobian_error
    );
    o += &eigenvalue_table(r, model);
    let _ = writeln!(
        o,
        "  max |closed form - numerical|: {:.1e}",
        r.closed_form_max_abs_diff
    );
    let verdict = match r.verdict {
        analysis::Verdict::Unstable => "unstable (some |lambda| > 1)",
        analysis::Verdict::Marginal => {
            "marginal (all |lambda| <= 1, some = 1: neutrally stable to first order)"
        }
        analysis::Verdict::AsymptoticallyStable => "asymptotically stable (all |lambda| < 1)",
        analysis::Verdict::Unreliable => {
            "unreliable (some |lambda| is within the eigenvalues' uncertainty of 1: the linearization cannot decide)"
        }
    };
    let _ = writeln!(
        o,
        "  verdict:      {verdict}; eigenvalue uncertainty {:.1e}",
        r.verdict_tolerance
    );
    let _ = writeln!(o, "  regime:       {}", regime(r));
    if !c.kappa_crit_eq16.is_nan() {
        let _ = writeln!(
            o,
            "  kappa_crit:   eq. 16 {:.6}; eq. 26 as printed (e = {}) {:.6}",
            c.kappa_crit_eq16, p.restitution, c.kappa_crit_eq26
        );
    }
    let _ = writeln!(
        o,
        "  energy:       eigenvalue 1 - (1+e) kappa_E y*^2 = {:.6}; kappa_Emax {:.6} s^2/m^2 re-derived, {:.6} as printed",
        c.energy_eigenvalue, c.kappa_e_max, c.kappa_e_max_as_printed
    );
    o
}

/// The `analyze --json` object: the serialized [`AnalysisReport`] with the eigenvalues as
/// `[re, im]` pairs (`eigenvalue_moduli` beside them) and the closed forms' eigenvalues
/// likewise.
fn analyze_json(name: &str, r: &AnalysisReport) -> Result<String, String> {
    let json_err = |e: serde_json::Error| format!("json: {e}");
    let mut v = serde_json::to_value(r).map_err(json_err)?;
    let obj = v
        .as_object_mut()
        .ok_or_else(|| "json: report is not an object".to_string())?;
    obj.insert(
        "eigenvalues".into(),
        serde_json::json!(r
            .eigenvalues
            .iter()
            .map(|e| [e.re, e.im])
            .collect::<Vec<_>>()),
    );
    obj.insert(
        "eigenvalue_moduli".into(),
        serde_json::json!(r.eigenvalues.iter().map(|e| e.modulus).collect::<Vec<_>>()),
    );
    if let Some(cf) = obj.get_mut("closed_form").and_then(|c| c.as_object_mut()) {
        let pred = &r.closed_form.predicted[..r.closed_form.count];
        cf.insert(
            "predicted".into(),
            serde_json::json!(pred.iter().map(|p| [p.0, p.1]).collect::<Vec<_>>()),
        );
    }
    obj.insert("scene".into(), serde_json::json!(name));
    serde_json::to_string(&v).map_err(json_err)
}

/// What `analyze` reports of a planar scene.
pub struct Analysis<'a> {
    name: &'a str,
    report: AnalysisReport,
    model: &'a PlanarModel,
}

impl Report for Analysis<'_> {
    fn text(&self) -> String {
        analyze_text(self.name, &self.report, self.model)
    }
    fn json(&self) -> Result<String, String> {
        analyze_json(self.name, &self.report)
    }
}

/// `dexter analyze` on a planar scene (the file names the scene).
pub fn analyze<'a>(file: &'a SceneFile, cfg: &'a PlanarConfig) -> Result<Analysis<'a>, Failure> {
    let report = analysis::analyze(&cfg.model).map_err(super::planar_failure)?;
    Ok(Analysis {
        name: &file.stem,
        report,
        model: &cfg.model,
    })
}
