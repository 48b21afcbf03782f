//! Critical speeds.
