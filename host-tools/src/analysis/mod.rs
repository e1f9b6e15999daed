//! What the data say about the model: the joint fit over a session
//! ([`fit`]), the search for the effects the baseline misses
//! ([`diagnose`]), the recordings that would show what a session cannot
//! ([`plan`]), the seed's own measurements beside both models
//! ([`seed_check`]), and the [`median`] they read robust levels with.

pub mod diagnose;
pub mod fit;
pub mod median;
pub mod plan;
pub mod seed_check;
