//! ROS 2 bags stored as MCAP (the default storage since ROS 2 Iron), read into the per-step rows
//! the estimators take, and estimates written back as MCAP that Foxglove and PlotJuggler plot
//! without plugins.
//!
//! # Mapping
//!
//! Each model input and output is read from one topic's field: `gnss_x` from `/gnss/odom`,
//! field `pose.pose.position.x`. A field path names nested fields with `.` and array elements
//! with `[i]` (`orientation_covariance[0]`, `data[2]`); `bool` and integer fields read as
//! numbers, a string is an error. [`Bag::inspect`] lists every topic's numeric field paths.
//! Messages are decoded from the schema the file carries: CDR with a `ros2msg` schema (what
//! ROS 2 records), or JSON (`json`, with a `jsonschema` schema or none); other encodings are
//! refused by name.
//!
//! # Time base
//!
//! Row `k` holds the input `u_k` and the measurement `y_{k+1}` taken after it (the convention of
//! `port-est`'s CSV files). Two time bases:
//!
//! - **Fixed step** ([`LogSpec::fixed_step`]): step `k` at `t_k = t0 + k·ts`, `t0` the stamp of
//!   the first message of a mapped topic in the file (or [`LogSpec::start_ns`]). Each input is
//!   held from its topic's latest message at or before `t_k`. An output is measured in step `k`
//!   when a message of its topic is stamped in `(t_k, t_k + ts]`; of several, the latest (and of
//!   equal stamps, the later in the file) counts; without one it is unmeasured (NaN, `measured`
//!   false). Steps run while `t_k` is at most the last mapped stamp.
//! - **Per message** ([`LogSpec::per_message`]): one step per message of a driving topic, at its
//!   stamp; the output window of step `k` runs to the next driving message, `(t_k, t_{k+1}]`. The
//!   last driving message, whose window has no end, makes no row.
//!
//! Steps before every input has had a message are skipped, and `k` counts the rows from 0:
//! the first row is the first step with all inputs.
//!
//! # Stamps
//!
//! By default a message's time is its MCAP log time (when the recorder received it: monotonic
//! per topic, and the same clock for every topic). With [`Stamps::Header`] it is the message's
//! `header.stamp` (sec + nanosec) for topics whose type has a `std_msgs/Header` (for JSON:
//! whose schema declares `header.stamp.sec` and `nanosec`), and the log time for the others.
//! A topic's stamps must not go back ([`Error::OutOfOrder`], naming the topic, both stamps and
//! the byte offset): sorting would hide two publishers on one topic or a clock jump. Across
//! topics, stamps may lag one another in the file by up to a *reorder window* (1 s by default,
//! [`LogSpec::reorder_window`]): a step is published once a stamp later than its window's end by
//! more than that has been read, and a message that would change a published step is an
//! [`Error::Late`].
//!
//! # Memory
//!
//! The file is memory-mapped, never read into the heap. Chunks are decompressed one at a time
//! (at most [`DEFAULT_MAX_CHUNK_BYTES`]); every length read from the file (records, strings,
//! sequences) is checked against the bytes that remain before it is used. Rows are streamed
//! ([`Rows`]): only messages not yet consumed by a step are kept (the reorder window's worth;
//! at most [`LogSpec::max_backlog`]). A damaged file gives the rows before the damage, then an
//! [`Error::Corrupt`] naming the record and its byte offset.
//!
//! # Example
//!
//! ```no_run
//! use ros_bag::{Bag, LogSpec, Stamps};
//!
//! let bag = Bag::open("run.mcap")?;
//! print!("{}", bag.inspect()); // topics, types, rates, numeric fields
//! let spec = LogSpec::fixed_step(0.01)
//!     .input("a", "/imu", "linear_acceleration.x")
//!     .input("delta", "/cmd", "twist.angular.z")
//!     .output("gnss_x", "/gnss/odom", "pose.pose.position.x")
//!     .output("gyro", "/imu", "angular_velocity.z")
//!     .stamps(Stamps::Header);
//! for row in bag.rows(&spec)? {
//!     let row = row?; // an error ends the rows; those before it stand
//!     println!("{} {} {:?} {:?} {:?}", row.k, row.t, row.u, row.y, row.measured);
//! }
//! # Ok::<(), ros_bag::Error>(())
//! ```
//!
//! # Writing
//!
//! [`CdrWriter`] encodes ROS 2 messages of one's own in CDR (synthetic bags for tests and
//! examples, written with the `mcap` crate).
//!
//! [`EstimateWriter`] writes one JSON message per step on a topic, with a JSON schema of plain
//! numbers named after the states (`{"k": 3, "t": 0.03, "x": {"px": 1.0}, "lower": {…},
//! "upper": {…}, "status": "converged"}`), log and publish time the step's time, so that
//! `/estimate.x.px` plots as it is. [`TopicCopy`] copies the input bag's topics into the same
//! file (schemas, channels and messages unchanged), interleaved with the estimates by log time, so
//! that one file holds data and estimates. Messages stream to a temporary file published on
//! [`EstimateWriter::finish`].
//!
//! ```no_run
//! use ros_bag::{Bag, Estimate, EstimateLayout, EstimateWriter, Spread};
//!
//! let layout = EstimateLayout::new("/estimate", ["px", "py"]).spread(Spread::Bounds).status(true);
//! let mut out = EstimateWriter::create("est.mcap", layout)?;
//! let (x, lo, hi) = ([1.0, 2.0], [0.5, 1.5], [1.5, 2.5]);
//! out.write(&Estimate { lower: Some(&lo), upper: Some(&hi), status: Some("converged"), ..Estimate::new(0, 1_700_000_000_000_000_000, &x) })?;
//! out.copy_topics(&Bag::open("run.mcap")?, &["/imu"])?;
//! out.finish()?;
//! # Ok::<(), ros_bag::Error>(())
//! ```

mod bag;
mod cdr;
mod cdr_writer;
mod container;
mod copy;
mod decoder;
mod error;
mod inspect;
mod json;
mod msgdef;
mod path;
mod rows;
mod writer;

pub use bag::{Bag, DEFAULT_MAX_CHUNK_BYTES};
pub use cdr_writer::{CdrWriteError, CdrWriter};
pub use copy::TopicCopy;
pub use error::{Error, Location, Result};
pub use inspect::{Inspection, TopicInfo};
pub use rows::{DEFAULT_MAX_BACKLOG, DEFAULT_REORDER_WINDOW, LogSpec, Mapping, Row, Rows, Stamps, TimeBase};
pub use writer::{ESTIMATE_SCHEMA, Estimate, EstimateLayout, EstimateWriter, Spread};
