//! Board image placeholder for host builds: the real image is built with `cargo fw`.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("plasma-bridge is firmware for the STM32L476RG: build it with `cargo fw`.");
}
