//! The running firmware: the debug probe ([`probe`]), its force stream
//! turned into a recording ([`stream`], [`capture`]) and the commands sent
//! to it ([`command`]).

pub mod capture;
pub(crate) mod causes;
pub mod command;
pub mod probe;
pub mod stream;
