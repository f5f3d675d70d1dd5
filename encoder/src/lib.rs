//! The `mocap` encoder library: read motion, encode it into `.mcb`
//! bitstreams, decode and evaluate them with the same `no_std` decoder the
//! MCU runs. The `mocap` command line is the `mocap-cli` crate; nothing here
//! parses arguments or prints errors — every area returns its typed error.
//!
//! Motion in and out: [`input`] (one entry point: BVH or ASF/AMC), [`bvh`],
//! [`asf`], [`c3d`] (marker files, [`markers`]), [`motion`], [`units`],
//! [`kinematics`], [`fixed`], [`generate`]. Coding: [`codec`], [`encode`], [`container`],
//! [`clipfile`], [`metrics`]. Servos: [`rig`], [`servo_clip`], [`play`].
//! The reports over them (bench, plots, Motion Track) are the
//! `mocap-report` crate.

pub mod asf;
pub mod bvh;
pub mod c3d;
pub mod clipfile;
pub mod codec;
pub mod contacts;
pub mod container;
pub mod encode;
pub mod entropy;
pub mod fixed;
pub mod generate;
pub mod input;
pub mod kinematics;
pub mod located;
pub mod markers;
pub mod metrics;
pub mod motion;
pub mod play;
pub mod rig;
mod rotation;
pub mod servo_clip;
pub mod show;
pub mod target;
pub mod units;
