//! What every workflow shares: the error type, provenance and input hashes, CSV tables, the printed summary, the advice of an error, the calibration options and their text forms, standard output.

pub(crate) mod advice;
#[cfg(feature = "clap")]
pub(crate) mod command_files;
pub(crate) mod error;
pub mod option_text;
pub(crate) mod options;
pub(crate) mod provenance;
pub(crate) mod stdout;
pub(crate) mod summary;
pub(crate) mod summary_text;
pub(crate) mod table;
