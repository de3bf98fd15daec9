//! The linearisation at a refinement's solution ([`AtSolution`]): its
//! problem (the freed parameters of the options, the refinement's weights),
//! its state and the undamped normal equations there, what the covariance and
//! the linearity check start from. The normal equations are those the
//! refinement kept ([`Linearization`]) when they are of the same fit, and
//! computed afresh otherwise.

use psdcal_solver::normal_equations::NormalEquations;
use psdcal_solver::solver;

use crate::problem::calibration_problem::{CalibrationProblem, FitState};
use crate::refine::options::RefineOptions;
use crate::refine::refined::{Linearization, Refined};
use crate::{CalibError, CalibrationData};

/// The fit of a refinement at its solution: its problem (the freed
/// parameters of the options, the refinement's weights), its state, and the
/// undamped normal equations there — what the covariance and the linearity
/// check start from, built once for both.
pub(crate) struct AtSolution<'a> {
    pub problem: CalibrationProblem<'a>,
    pub state: FitState,
    pub ne: NormalEquations,
}

impl<'a> AtSolution<'a> {
    /// Linearises `refined`'s fit for the cost and freed parameters of `options`.
    pub(crate) fn new(
        data: &'a CalibrationData,
        refined: &'a Refined,
        options: &'a RefineOptions,
    ) -> Result<Self, CalibError> {
        let names = options.free_names();
        let problem = CalibrationProblem::new(
            data,
            options.cost,
            &refined.model,
            &names,
            refined.weights.as_ref(),
        )?
        .with_prior(&refined.model, options.prior.as_ref())?;
        let state = FitState {
            model: refined.model.clone(),
            poses: refined.poses.clone(),
        };
        let ne = match Linearization::of(refined, data, options) {
            Some(ne) => ne,
            None => solver::normal_equations(&problem, &state, options.robust)?,
        };
        Ok(Self { problem, state, ne })
    }
}

#[cfg(test)]
mod tests {
    //! The linearisation a refinement keeps against one computed afresh at
    //! its solution, and its invalidation when the solution is changed.

    use super::*;
    use crate::refine::solve::refine;
    use psdcal_model::CostKind;
    use psdcal_model::{Param, PsdGeometry, SensorModel};
    use psdcal_solver::solver;
    use psdcal_solver::solver::RobustLoss;
    use psdcal_testkit::{add_noise, covering_poses, image_points, perturbed, scatter, PointKind};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn noisy_fit(options: &RefineOptions) -> (CalibrationData, Refined) {
        let truth = SensorModel::paper_lens2();
        let template = scatter(14);
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let poses = covering_poses(&truth, &template, 6, &mut rng);
        let mut points = image_points(&truth, &template, &poses, PointKind::Measured);
        let noise = rand_distr::Normal::new(0.0, 2e-3).expect("a valid σ");
        add_noise(&mut points, &noise, &mut rng);
        let data = CalibrationData::from_points(&template, &[], points, PsdGeometry::default());
        let (m0, p0) = perturbed(&truth, &poses);
        let refined = refine(&data, m0, &p0, options).expect("the fit converges");
        (data, refined)
    }

    /// The normal equations computed afresh at `refined`'s solution.
    fn fresh(
        data: &CalibrationData,
        refined: &Refined,
        options: &RefineOptions,
    ) -> NormalEquations {
        let problem = CalibrationProblem::new(
            data,
            options.cost,
            &refined.model,
            &options.free_names(),
            refined.weights.as_ref(),
        )
        .expect("a valid problem");
        let state = FitState {
            model: refined.model.clone(),
            poses: refined.poses.clone(),
        };
        solver::normal_equations(&problem, &state, options.robust).expect("it evaluates")
    }

    fn assert_same(a: &NormalEquations, b: &NormalEquations) {
        assert_eq!(a.u, b.u);
        assert_eq!(a.g_a, b.g_a);
        assert_eq!(a.v, b.v);
        assert_eq!(a.w, b.w);
        assert_eq!(a.g_b, b.g_b);
    }

    #[test]
    fn kept_linearization_is_the_one_at_the_solution() {
        for options in [
            RefineOptions::default(),
            RefineOptions {
                cost: CostKind::Image,
                robust: Some(RobustLoss::Huber { scale: 4e-3 }),
                ..RefineOptions::default()
            },
        ] {
            let (data, refined) = noisy_fit(&options);
            // The fit ends on a negligible predicted decrease, linearised at
            // its solution: the equations are kept, bit for bit those of a
            // new linearisation.
            let kept = Linearization::of(&refined, &data, &options).expect("kept");
            assert_same(&kept, &fresh(&data, &refined, &options));
            let at = AtSolution::new(&data, &refined, &options).expect("linearises");
            assert_same(&at.ne, &kept);
        }
    }

    #[test]
    fn kept_linearization_is_not_used_for_another_fit() {
        let options = RefineOptions::default();
        let (data, refined) = noisy_fit(&options);
        // Other options, another solution, another data set: recomputed.
        let other = RefineOptions {
            free: vec![Param::F, Param::Cx, Param::Cy, Param::K1],
            ..options.clone()
        };
        assert!(Linearization::of(&refined, &data, &other).is_none());
        let mut moved = refined.clone();
        moved.poses[0].t.z += 1e-3;
        assert!(Linearization::of(&moved, &data, &options).is_none());
        let at = AtSolution::new(&data, &moved, &options).expect("linearises");
        assert_same(&at.ne, &fresh(&data, &moved, &options));
        let mut fewer = data.clone();
        fewer.images.pop();
        assert!(Linearization::of(&refined, &fewer, &options).is_none());
    }
}
