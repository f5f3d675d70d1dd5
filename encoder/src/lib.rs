//! The `mocap` encoder: read motion, encode it into `.mcb` bitstreams,
//! decode and evaluate them with the same `no_std` decoder the MCU runs.

pub mod bench;
pub mod bvh;
pub mod clipfile;
pub mod codec;
pub mod container;
pub mod encode;
pub mod fixed;
pub mod generate;
pub mod kinematics;
pub mod metrics;
pub mod motion;
pub mod play;
pub mod plot;
pub mod rig;
pub mod servo_clip;
pub mod track;
pub mod units;
