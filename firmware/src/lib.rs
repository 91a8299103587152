//! The bridge's behaviour, free of any HAL: built and tested on the host.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod time;
pub mod port;
pub mod link;
