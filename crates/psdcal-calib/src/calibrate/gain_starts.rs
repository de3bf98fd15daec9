//! The refinement with the channel gains freed (docs/model.md §1, §4.6),
//! from several starts: the lowest cost among the converged ones with a
//! plausible focal length wins. The gains and the intrinsics trade against
//! each other (an imbalance looks like a shifted centre and a distortion),
//! so one start can settle in a wrong minimum, whose residual then stands
//! out by orders of magnitude.
//!
//! The starts: (a) the gains freed from unit at once; (b) the gains held at
//! unit first, then freed from that fit; (c) with a nominal focal length
//! and a closed-form start, the focal-length search around the nominal
//! value; (d) with a refined closed-form start, the unrefined closed form
//! (the paper's start), which has not absorbed the imbalance into the
//! intrinsics. A focal length outside 0.1–100 × the sensor's diagonal is a
//! runaway along a degenerate direction and never wins.

use psdcal_model::Model;

use crate::calibrate::options::{seeded_base, CalibrateOptions};
use crate::data::CalibrationData;
use crate::refine::global::{refine_global, GlobalOptions, GlobalReport};
use crate::refine::options::RefineOptions;
use crate::refine::refined::Refined;
use crate::refine::solve::refine;
use crate::start::initialize::{initialize, InitOptions, InitRoute, Initialization};
use crate::CalibError;

/// The refinement with the gains freed from the competing starts (module
/// documentation), with the global search's report of the winner when it
/// had one and the name of the winning start.
pub(crate) fn refine_from_gain_starts(
    data: &CalibrationData,
    init: &Initialization,
    start: &Model,
    options: &CalibrateOptions,
    global_options: &GlobalOptions,
) -> Result<(Refined, Option<GlobalReport>, String), CalibError> {
    // Several starts, the lowest cost among the converged ones wins: (a)
    // the start with the gains freed from unit at once; (b) the fit with
    // the gains held at unit first, then freed; (c) when a nominal focal
    // length is given and the closed form supplied the start, the
    // focal-length search around the nominal value, gains freed. A wrong
    // minimum stands out by a residual orders of magnitude larger.
    let (a, global) = refine_global(data, start, &init.poses, &options.refine, global_options)?;
    let mut best = (a, global, "gains freed from the start");
    // A focal length far outside any lens for this sensor (the start's
    // plausible range) is a runaway along a degenerate direction, never
    // a better answer.
    let diagonal = data.geometry.lx.hypot(data.geometry.ly);
    let plausible = |r: &Refined| {
        let f = r.model.get("f").unwrap_or(f64::NAN);
        f > 0.1 * diagonal && f < 100.0 * diagonal
    };
    let mut consider = |candidate: Result<Refined, CalibError>, name: &'static str| {
        if let Ok(c) = candidate {
            let incumbent = &best.0;
            let incumbent_usable = incumbent.report.termination.converged() && plausible(incumbent);
            if c.report.termination.converged()
                && plausible(&c)
                && (c.cost < incumbent.cost || !incumbent_usable)
            {
                best = (c, None, name);
            }
        }
    };
    // The gains freed from the start another start option finds.
    let freed_from = |init_options: &InitOptions| {
        initialize(data, init_options).and_then(|i| {
            let m = seeded_base(options, &i.model)?;
            refine_global(data, &m, &i.poses, &options.refine, global_options).map(|(r, _)| r)
        })
    };
    let fixed = RefineOptions {
        fit_gains: false,
        ..options.refine.clone()
    };
    let b = refine_global(data, start, &init.poses, &fixed, global_options)
        .and_then(|(plain, _)| refine(data, &plain.model, &plain.poses, &options.refine));
    consider(b, "gains fixed first, then freed");
    if options.init.focal_guess.is_some() && init.report.route == InitRoute::ClosedForm {
        let searched = InitOptions {
            use_closed_form: false,
            ..options.init
        };
        consider(
            freed_from(&searched),
            "search around the nominal focal length, gains freed",
        );
    }
    if init.report.route == InitRoute::ClosedForm && options.init.refine_start {
        // The refined closed form has absorbed the gain imbalance into
        // the intrinsics; the unrefined closed form (the paper's start)
        // has not, and competes with the gains freed.
        let plain = InitOptions {
            refine_start: false,
            ..options.init
        };
        consider(freed_from(&plain), "closed form unrefined, gains freed");
    }
    let (r, g, name) = best;
    Ok((r, g, name.to_string()))
}
