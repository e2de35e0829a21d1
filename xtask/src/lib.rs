//! The workspace's automation, as a library so that end-to-end tests can call it; the `xtask`
//! binary (`cargo xtask …`) is a thin command-line layer over it.

pub mod args;

pub mod reproduce;
pub mod sdplib;
pub mod test_suite;
