//! The bench as one workflow: a session's protocol ([`protocol`]) run
//! against the board through one link ([`run`]), each recording written
//! as it ends.

pub mod protocol;
pub mod run;
