//! What a build holds its fitted model in, picked from its segment count
//! at compile time: a [`Shaper`] up to [`MAX_SHAPED_SEGMENTS`](crate::shaper::MAX_SHAPED_SEGMENTS), above it
//! an [`Unshaped`], which refuses a model and a motion as the shaper does
//! there (no model is ever checked above the bound) but holds no strip.
//! An unused `Option` of a checked model still takes the strip's size in
//! static RAM: about 10 KiB at N = 8, where the board's stack needs it.
//!
//! ```
//! use finrs_controller::model_holder::{Fits, HoldsModel, Pick, Unshaped};
//! use finrs_controller::shaper::{Shaper, ELEMENTS, MAX_SHAPED_SEGMENTS};
//! use model_core::state_len;
//!
//! const N: usize = 8;
//! const S: usize = state_len(N, ELEMENTS);
//! type Models = <Fits<{ N <= MAX_SHAPED_SEGMENTS }> as Pick<N, ELEMENTS, S>>::Holder;
//! assert_eq!(core::mem::size_of::<Models>(), 0);
//! assert!(core::mem::size_of::<Shaper<N, ELEMENTS, S>>() > 9_000);
//! let _: Unshaped<N> = Models::empty();
//! ```

use core::convert::Infallible;

use finrs_drive::Envelope;
use finrs_frames::{ModelRecord, Motion};

use crate::shaper::{CheckedModel, ShapeRefused, ShapedMotion, Shaper};

/// A holder of the model a SetModel sent, for `N` segments: what
/// [`crate::shaper::command`] shapes with.
pub trait HoldsModel<const N: usize> {
    /// A model checked and built, ready for [`HoldsModel::install`].
    type Checked;

    /// No model yet: every motion is refused.
    fn empty() -> Self;

    /// Checks `record` for a strip sampled every `dt_s`
    /// ([`Shaper::check`]).
    fn check(record: &ModelRecord, dt_s: f64) -> Result<Self::Checked, ShapeRefused>;

    /// Uses `model` from now on.
    fn install(&mut self, model: Self::Checked);

    /// The program that makes `motion` ([`Shaper::program`]).
    fn program(
        &self,
        motion: &Motion,
        envelope: Envelope,
        limit_v: f32,
        t_session_s: f32,
    ) -> Result<ShapedMotion<N>, ShapeRefused>;
}

impl<const N: usize, const E: usize, const S: usize> HoldsModel<N> for Shaper<N, E, S> {
    type Checked = CheckedModel<N, E, S>;

    fn empty() -> Self {
        Self::new()
    }

    fn check(record: &ModelRecord, dt_s: f64) -> Result<Self::Checked, ShapeRefused> {
        Shaper::check(record, dt_s)
    }

    fn install(&mut self, model: Self::Checked) {
        Shaper::install(self, model);
    }

    fn program(
        &self,
        motion: &Motion,
        envelope: Envelope,
        limit_v: f32,
        t_session_s: f32,
    ) -> Result<ShapedMotion<N>, ShapeRefused> {
        Shaper::program(self, motion, envelope, limit_v, t_session_s)
    }
}

/// The holder of a build above [`MAX_SHAPED_SEGMENTS`](crate::shaper::MAX_SHAPED_SEGMENTS): a model is refused
/// for the segment count, a motion for want of a model, as a [`Shaper`]
/// refuses them there.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unshaped<const N: usize>;

impl<const N: usize> HoldsModel<N> for Unshaped<N> {
    /// Never made: nothing is checked.
    type Checked = Infallible;

    fn empty() -> Self {
        Self
    }

    fn check(_: &ModelRecord, _: f64) -> Result<Infallible, ShapeRefused> {
        Err(ShapeRefused::TooManySegments(N))
    }

    fn install(&mut self, model: Infallible) {
        match model {}
    }

    fn program(
        &self,
        _: &Motion,
        _: Envelope,
        _: f32,
        _: f32,
    ) -> Result<ShapedMotion<N>, ShapeRefused> {
        Err(ShapeRefused::NoModel)
    }
}

/// Whether a build's segment count is one a model is checked for:
/// `Fits<{ N <= MAX_SHAPED_SEGMENTS }>`.
pub struct Fits<const SHAPED: bool>;

/// The holder [`Fits`] picks, for `N` segments of `E` elements (`S` the
/// strip's state length).
pub trait Pick<const N: usize, const E: usize, const S: usize> {
    /// A [`Shaper`] or an [`Unshaped`].
    type Holder: HoldsModel<N>;
}

impl<const N: usize, const E: usize, const S: usize> Pick<N, E, S> for Fits<true> {
    type Holder = Shaper<N, E, S>;
}

impl<const N: usize, const E: usize, const S: usize> Pick<N, E, S> for Fits<false> {
    type Holder = Unshaped<N>;
}
