//! Reports over `.mcb` clips and their sources, built on the encoder
//! library: the rate–distortion table of `mocap bench` ([`bench`](mod@bench),
//! with the size references users would pick instead, [`bench::baseline`]),
//! the plots of `bench --plot` and `eval --plot` ([`plot`]), Motion Track
//! pictures ([`track`]) and the 3-D player page of `mocap view` ([`view`]).
//! Kept apart from `mocap-encoder` so the codec library does not carry a
//! plotting stack.

pub mod bench;
pub mod plot;
pub mod track;
pub mod view;
