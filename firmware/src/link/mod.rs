//! The power-supply link (see notes/LINK-DESIGN.md): a sans-IO state machine that speaks
//! Modbus ASCII to Powermax units and `>ID data CK<` to HPR / MaxPro200 units.

pub mod config;
pub mod diagnostics;
pub mod transaction;
