//! The bench as one workflow: a session's protocol
//! ([`protocol`](crate::protocol)) run
//! against the board through one link ([`run`]), each recording written
//! as it ends; a live view that records and commands ([`live`]).

pub mod live;
pub mod run;
