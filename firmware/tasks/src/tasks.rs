//! The board's task wrappers, written once: `#[embassy_executor::task]` functions cannot be
//! generic, so each board expands [`board_tasks!`](crate::board_tasks) with its [`Board`]
//! type, which declares the four tasks with that board's concrete types. Each wrapper returns
//! the shared body's future rather than being an `async fn` around `.await`: that future would
//! keep the arguments twice (its own and the body's).
//!
//! [`Board`]: crate::Board

/// Declares, in the calling module, the board's four tasks around the shared bodies:
/// `io_task` ([`io::run`](crate::io::run)), `bridge_task` ([`bridge::run`](crate::bridge::run)),
/// `settings_task` ([`settings::run`](crate::settings::run)) and `heartbeat_task`
/// ([`progress::heartbeat`](crate::progress::heartbeat)), with the types of `$board` (a
/// [`Board`](crate::Board)). The calling crate depends on `embassy-executor`.
///
/// ```ignore
/// plasma_tasks::board_tasks!(Nucleo);
/// spawner.spawn(heartbeat_task(led, progress).unwrap());
/// ```
#[macro_export]
macro_rules! board_tasks {
    ($board:ty) => {
        /// The I/O task ([`plasma_tasks::io::run`]).
        #[::embassy_executor::task]
        pub fn io_task(
            inputs: <$board as $crate::Board>::InputPins,
            outputs: <$board as $crate::Board>::OutputPins,
            config: ::plasma_firmware::io::IoConfig,
            progress: ::plasma_firmware::watchdog::TaskId,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::io::run(inputs, outputs, config, progress)
        }

        /// The bridge task ([`plasma_tasks::bridge::run`]).
        #[::embassy_executor::task]
        pub fn bridge_task(
            bridge: &'static mut ::plasma_firmware::bridge::Bridge,
            ps: <$board as $crate::Board>::PsUart,
            cnc: <$board as $crate::Board>::CncUart,
            io: $crate::io::BoardIo,
            progress: ::plasma_firmware::watchdog::TaskId,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::bridge::run::<$board>(bridge, ps, cnc, io, progress)
        }

        /// The settings task ([`plasma_tasks::settings::run`]).
        #[::embassy_executor::task]
        pub fn settings_task(
            store: ::core::option::Option<$crate::settings::Store<$board>>,
            progress: ::plasma_firmware::watchdog::TaskId,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::settings::run::<$board>(store, progress)
        }

        /// The heartbeat task ([`plasma_tasks::progress::heartbeat`]).
        #[::embassy_executor::task]
        pub fn heartbeat_task(
            led: <$board as $crate::Board>::Led,
            progress: ::plasma_firmware::watchdog::TaskId,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::progress::heartbeat(led, progress)
        }
    };
}
