//! The board's task wrappers, written once: `#[embassy_executor::task]` functions cannot be
//! generic, so each board expands [`board_tasks!`](crate::board_tasks) with its [`Board`]
//! type, which declares the six tasks with that board's concrete types, and `start_tasks`,
//! which spawns each in the executor [`layout`](crate::layout) gives it. Each wrapper returns
//! the shared body's future rather than being an `async fn` around `.await`: that future would
//! keep the arguments twice (its own and the body's).
//!
//! [`Board`]: crate::Board

/// Declares, in the calling module, the board's six tasks around the shared bodies:
/// `io_task` ([`io::run`](crate::io::run)), `bridge_task` ([`bridge::run`](crate::bridge::run)),
/// `settings_task` ([`settings::run`](crate::settings::run)), `history_task`
/// ([`history::run`](crate::history::run)), `heartbeat_task`
/// ([`progress::heartbeat`](crate::progress::heartbeat)) and `judge_task`
/// ([`progress::judge`](crate::progress::judge)), with the types of `$board` (a
/// [`Board`](crate::Board)), and `start_tasks`, the one task layout
/// ([`layout`](crate::layout)). The calling crate depends on `embassy-executor`.
///
/// ```ignore
/// plasma_tasks::board_tasks!(Nucleo);
/// start_tasks(thread_spawner, tasks);
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
            progress: ::plasma_firmware::platform::watchdog::TaskId,
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
            progress: ::plasma_firmware::platform::watchdog::TaskId,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::bridge::run::<$board>(bridge, ps, cnc, io, progress)
        }

        /// The settings task ([`plasma_tasks::settings::run`]).
        #[::embassy_executor::task]
        pub fn settings_task(
            store: ::core::option::Option<$crate::settings::Store<$board>>,
            progress: ::plasma_firmware::platform::watchdog::TaskId,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::settings::run::<$board>(store, progress)
        }

        /// The history task ([`plasma_tasks::history::run`]).
        #[::embassy_executor::task]
        pub fn history_task(
            store: ::core::option::Option<$crate::history::Store<$board>>,
            progress: ::plasma_firmware::platform::watchdog::TaskId,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::history::run::<$board>(store, progress)
        }

        /// The heartbeat task ([`plasma_tasks::progress::heartbeat`]).
        #[::embassy_executor::task]
        pub fn heartbeat_task(
            led: <$board as $crate::Board>::Led,
            progress: ::plasma_firmware::platform::watchdog::TaskId,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::progress::heartbeat(led, progress)
        }

        /// The stall judge ([`plasma_tasks::progress::judge`]).
        #[::embassy_executor::task]
        pub fn judge_task(
            watchdog: <$board as $crate::Board>::Watchdog,
        ) -> impl ::core::future::Future<Output = ()> {
            $crate::progress::judge(watchdog)
        }

        /// Spawns every task in its executor ([`plasma_tasks::layout`]): the I/O task on the
        /// I/O executor, bridge, settings, history and heartbeat on `thread`, then the stall judge on
        /// its executor above them all, once every task it judges is registered. A spawn
        /// fails only if a task is spawned twice, a build mistake: panic = safe state.
        pub fn start_tasks(
            thread: ::embassy_executor::Spawner,
            tasks: $crate::layout::Tasks<$board>,
        ) {
            use $crate::layout;
            use $crate::progress::register;
            let io = register("io", layout::IO_DEADLINE);
            let bridge = register("bridge", layout::BRIDGE_DEADLINE);
            let settings = register("settings", layout::SETTINGS_DEADLINE);
            let history = register("history", layout::HISTORY_DEADLINE);
            let heartbeat = register("heartbeat", layout::HEARTBEAT_DEADLINE);
            layout::io_executor()
                .spawn(io_task(tasks.inputs, tasks.outputs, tasks.io_config, io).unwrap());
            thread.spawn(
                bridge_task(
                    tasks.bridge,
                    tasks.ps,
                    tasks.cnc,
                    $crate::io::BoardIo,
                    bridge,
                )
                .unwrap(),
            );
            thread.spawn(settings_task(tasks.store, settings).unwrap());
            thread.spawn(history_task(tasks.history, history).unwrap());
            thread.spawn(heartbeat_task(tasks.led, heartbeat).unwrap());
            layout::judge_executor().spawn(judge_task(tasks.watchdog).unwrap());
        }
    };
}
