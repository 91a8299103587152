//! Simulated power supplies and test harness for the plasma-bridge.
pub mod decode;
