//! ROS 2 bags stored as MCAP.

mod bag;
mod cdr;
mod container;
mod decoder;
mod error;
mod json;
mod msgdef;
mod path;
mod rows;

pub use bag::{Bag, DEFAULT_MAX_CHUNK_BYTES};
pub use error::{Error, Location, Result};
pub use rows::{DEFAULT_MAX_BACKLOG, DEFAULT_REORDER_WINDOW, LogSpec, Mapping, Row, Rows, Stamps, TimeBase};
