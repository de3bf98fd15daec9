//! The model the data choose (docs/model.md §4.8): each image's influence on
//! a fit from its linearisation ([`influence`]: leave-one-image-out
//! estimates and held-out angle errors without refitting), the score test
//! that spares refitting a group the data do not ask for ([`screen`]), a
//! candidate group's fit and score ([`candidate`]), and the choice among
//! nested parameter sets by their held-out error ([`choose`]), and the
//! uncertainty the choice itself adds ([`choice_spread`]).

pub mod candidate;
pub mod choice_spread;
pub mod choose;
pub mod influence;
pub mod screen;
