//! The bridge's thread-mode loop: both serial ports, the exchange with the I/O task, and
//! settings saves, around a sans-IO bridge.
//!
//! The board runs one [`Supervisor::turn`] after another in a task; host tests run it with
//! fake ports and a virtual clock. One turn:
//!
//! 1. takes the I/O task's latest levels (each unit's set's) and events and passes them to
//!    the bridge, each for its unit;
//! 2. passes every byte already waiting in either port to the bridge (so a reply that came in
//!    time is not taken for a time-out when the bridge is polled);
//! 3. transmits the bridge's power-supply frames ([`PsPort`]; asking for them polls it),
//!    polls it again (the link's time-outs run while frames are asked for, and may raise
//!    events) and writes its CNC output; when the
//!    CNC framing changed (`CONFIG cnc_baud|cnc_parity|cnc_stop_bits`), waits until that
//!    output has left (the reply to the CONFIG goes out at the old framing) and switches the
//!    CNC port;
//! 4. hands the number of units, each unit's supply state and the I/O settings to the I/O task
//!    when they changed, a save
//!    request to the settings saver, and the history's drafts (as many as it has room for)
//!    and a `HISTORY` request to the [`HistoryKeeper`];
//! 5. waits for the first of: bytes on either port, an I/O event, the end of a save, the
//!    history's answer, the bridge's `poll_at` (at most [`MAX_WAIT`], so the caller reports
//!    progress regularly).
//!
//! CNC output is written in pieces of at most the port's buffer size, each after the
//! previous one has left (`flush`): a bounded write per turn, so a long reply never holds the
//! loop while the power-supply side waits (the boards' driver, `plasma_tasks::uart`, would
//! otherwise wait for ring space inside the write).

use core::future::{Future, pending};

use embassy_futures::select::{Either6, select6};
use embassy_futures::yield_now;
use embedded_io_async::Read;

use crate::io::{Inputs, IoConfig, IoEvent, Outputs, SupplyState};
use crate::platform::pins::{UNIT_SETS, UnitSet};
use crate::platform::runner::{
    Clock, ConfigurablePort, MAX_WAIT, PS_RX_CHUNK, PortError, PsEndpoint, PsPort,
    UnsupportedConfig,
};

use crate::storage::history::{Draft, HistoryAnswer, HistoryRequest, HistoryUnavailable};
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Instant;

/// What the supervisor needs from the bridge ([`Bridge`](crate::bridge::Bridge) implements it; the names follow
/// its API).
pub trait BridgeEndpoint: PsEndpoint {
    /// The settings a save request carries.
    type Saved;
    /// Why a save failed.
    type SaveError;
    /// Bytes from the CNC.
    fn handle_cnc_rx(&mut self, now: Instant, bytes: &[u8]);
    /// Bytes to write to the CNC.
    fn poll_cnc_output(&mut self) -> Option<&[u8]>;
    /// The framing the CNC port must use.
    fn cnc_port_config(&self) -> PortConfig;
    /// Let time pass (asking for a frame, [`PsEndpoint::poll_ps_transmit`], does too).
    fn poll(&mut self, now: Instant);
    /// How many units it drives (the I/O task keeps the sets of the others inert).
    fn unit_count(&self) -> usize;
    /// What unit `unit`'s I/O must know about its supply (0 = the first unit).
    fn supply_state_of(&self, unit: usize) -> SupplyState;
    /// The I/O settings (they change with CONFIG commands).
    fn io_config(&self) -> IoConfig;
    /// Unit `unit`'s latest levels in the I/O task.
    fn set_io_snapshot_of(&mut self, unit: usize, inputs: Inputs, outputs: Outputs);
    /// An event of unit `unit`'s I/O.
    fn on_io_event_of(&mut self, unit: usize, now: Instant, event: IoEvent);
    /// Settings to store, after a CONFIG SAVE.
    fn take_save_request(&mut self) -> Option<Self::Saved>;
    /// How the store went.
    fn save_finished(&mut self, now: Instant, result: Result<(), Self::SaveError>);
    /// The oldest event waiting for the history.
    fn take_history_draft(&mut self) -> Option<Draft>;
    /// Whether events are still waiting for the history.
    fn history_drafts_waiting(&self) -> bool;
    /// What `HISTORY` asks of the history's store.
    fn take_history_request(&mut self) -> Option<HistoryRequest>;
    /// The store's answer.
    fn history_finished(&mut self, now: Instant, answer: &HistoryAnswer);
}

/// The supervisor's side of the exchange with the I/O task, which runs one unit's I/O per set
/// of the pin table ([`UnitSet`]).
pub trait IoExchange {
    /// Unit `unit`'s latest levels, if new ones were published since the last call.
    fn take_snapshot(&mut self, unit: UnitSet) -> Option<(Inputs, Outputs)>;
    /// The next event and its unit, if one is waiting.
    fn try_event(&mut self) -> Option<(UnitSet, Instant, IoEvent)>;
    /// Completes when an event is waiting (without taking it).
    fn event_ready(&mut self) -> impl Future<Output = ()>;
    /// Hand how many units the bridge drives to the I/O task: the sets from that index on are
    /// inert (START off, no events), whatever the settings allow.
    fn send_unit_count(&mut self, count: usize);
    /// Hand unit `unit`'s new supply state to the I/O task.
    fn send_supply(&mut self, unit: UnitSet, supply: SupplyState);
    /// Hand new I/O settings to the I/O task.
    fn send_io_config(&mut self, config: IoConfig);
}

/// Stores settings in the background (the board: a flash task).
pub trait SettingsSaver<S, E> {
    /// Start storing `settings`.
    fn start(&mut self, settings: S);
    /// Completes with the result of the save started last (cancel-safe).
    fn finished(&mut self) -> impl Future<Output = Result<(), E>>;
}

/// Keeps the history in the background (the board: a flash task; the host: a store over a
/// RAM flash): writes drafts, and reads or erases for `HISTORY` with
/// [`serve`](crate::storage::history::serve).
pub trait HistoryKeeper {
    /// Whether one more draft can be taken now (the drafts wait in the bridge meanwhile).
    fn has_room(&self) -> bool;
    /// Write `draft` (the caller checked [`HistoryKeeper::has_room`]).
    fn record(&mut self, draft: Draft);
    /// Start carrying out `request`.
    fn start(&mut self, request: HistoryRequest);
    /// Completes with the answer to the request started last (cancel-safe).
    fn finished(&mut self) -> impl Future<Output = HistoryAnswer>;
    /// Whether it keeps drafts at all (a `HISTORY` waits for the drafts noted before it only
    /// then).
    fn keeps_drafts(&self) -> bool {
        true
    }
}

/// No history kept: drafts stay in the bridge's bounded queue (dropped and counted when it
/// is full) and `HISTORY` is answered `ERR STORAGE`.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoHistory;

impl HistoryKeeper for NoHistory {
    fn has_room(&self) -> bool {
        false
    }
    fn record(&mut self, _draft: Draft) {}
    fn start(&mut self, _request: HistoryRequest) {}
    async fn finished(&mut self) -> HistoryAnswer {
        Err(HistoryUnavailable)
    }
    fn keeps_drafts(&self) -> bool {
        false
    }
}

/// A port failed during a turn (the turn ends there; the next one starts afresh).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TurnError<PsError, CncError> {
    /// The power-supply port.
    Ps(PortError<PsError>),
    /// The CNC port failed to read.
    CncRead(CncError),
    /// The CNC port failed to write (the output is lost).
    CncWrite(CncError),
    /// The CNC port reported end of input.
    CncClosed,
    /// The CNC port cannot run the framing the settings ask for (it keeps its old one; not
    /// retried until the settings ask for another).
    CncUnsupported(PortConfig),
}

/// Bytes taken from the CNC port per read.
pub const CNC_RX_CHUNK: usize = 64;

/// The loop around a bridge.
pub struct Supervisor<P, C, I, V, H = NoHistory> {
    ps: PsPort<P>,
    cnc: C,
    cnc_piece: usize,
    /// The CNC framing last set (or refused); `None`: unknown, the first turn sets it.
    cnc_framing: Option<PortConfig>,
    io: I,
    saver: V,
    history: H,
    sent_unit_count: Option<usize>,
    /// Each set's supply state last sent.
    sent_supply: [Option<SupplyState>; UNIT_SETS],
    sent_io_config: Option<IoConfig>,
    saving: bool,
    reading_history: bool,
}

type TurnResult<T, P, C> = core::result::Result<
    T,
    TurnError<
        <P as embedded_io_async::ErrorType>::Error,
        <C as embedded_io_async::ErrorType>::Error,
    >,
>;

impl<P, C, I, V> Supervisor<P, C, I, V>
where
    P: ConfigurablePort,
    C: ConfigurablePort,
    I: IoExchange,
{
    /// A supervisor over the PS port, the CNC port (whose transmit buffer holds
    /// `cnc_tx_buffer` bytes), the I/O exchange and the settings saver; no history is kept
    /// until [`Supervisor::with_history`].
    pub fn new(ps: P, cnc: C, cnc_tx_buffer: usize, io: I, saver: V) -> Self {
        Supervisor {
            ps: PsPort::new(ps),
            cnc,
            cnc_piece: cnc_tx_buffer.max(1),
            cnc_framing: None,
            io,
            saver,
            history: NoHistory,
            sent_unit_count: None,
            sent_supply: [None; UNIT_SETS],
            sent_io_config: None,
            saving: false,
            reading_history: false,
        }
    }

    /// The history is kept by `history`.
    pub fn with_history<H: HistoryKeeper>(self, history: H) -> Supervisor<P, C, I, V, H> {
        let Supervisor {
            ps,
            cnc,
            cnc_piece,
            cnc_framing,
            io,
            saver,
            sent_unit_count,
            sent_supply,
            sent_io_config,
            saving,
            ..
        } = self;
        Supervisor {
            ps,
            cnc,
            cnc_piece,
            cnc_framing,
            io,
            saver,
            history,
            sent_unit_count,
            sent_supply,
            sent_io_config,
            saving,
            reading_history: false,
        }
    }
}

impl<P, C, I, V, H> Supervisor<P, C, I, V, H>
where
    P: ConfigurablePort,
    C: ConfigurablePort,
    I: IoExchange,
    H: HistoryKeeper,
{
    /// The CNC port already runs at `framing` (the board opened it at the bridge's): the first
    /// turn leaves it as it is instead of setting it again.
    pub fn with_cnc_framing(mut self, framing: PortConfig) -> Self {
        self.cnc_framing = Some(framing);
        self
    }

    /// The CNC framing last set (or refused).
    pub fn cnc_framing(&self) -> Option<PortConfig> {
        self.cnc_framing
    }

    /// The power-supply port's line settings last applied.
    pub fn ps_framing(&self) -> Option<PortConfig> {
        self.ps.applied
    }

    /// The I/O exchange.
    #[cfg(test)]
    pub(crate) fn io(&mut self) -> &mut I {
        &mut self.io
    }

    /// The settings saver.
    #[cfg(test)]
    pub(crate) fn saver(&mut self) -> &mut V {
        &mut self.saver
    }

    /// True while a save is under way.
    #[cfg(test)]
    pub(crate) fn is_saving(&self) -> bool {
        self.saving
    }

    /// One turn (see the module documentation).
    pub async fn turn<B, K>(&mut self, bridge: &mut B, clock: &K) -> TurnResult<(), P, C>
    where
        B: BridgeEndpoint,
        V: SettingsSaver<B::Saved, B::SaveError>,
        K: Clock,
    {
        self.exchange_in(bridge);
        self.ps
            .drain_ready(bridge, clock)
            .await
            .map_err(TurnError::Ps)?;
        self.drain_cnc(bridge, clock).await?;

        // Asking for frames polls the bridge; it also runs the link's time-outs, whose events
        // the bridge moves into the session (replies, event lines) only when polled again.
        self.ps
            .transmit(bridge, clock)
            .await
            .map_err(TurnError::Ps)?;
        bridge.poll(clock.now());
        while let Some(output) = bridge.poll_cnc_output() {
            for piece in output.chunks(self.cnc_piece) {
                self.cnc.flush().await.map_err(TurnError::CncWrite)?;
                self.cnc
                    .write_all(piece)
                    .await
                    .map_err(TurnError::CncWrite)?;
            }
        }
        self.follow_cnc_framing(bridge).await?;

        self.exchange_out(bridge);
        if !self.saving
            && let Some(settings) = bridge.take_save_request()
        {
            self.saver.start(settings);
            self.saving = true;
        }
        self.exchange_history(bridge);

        self.wait(bridge, clock).await
    }

    /// Switches the CNC port to the bridge's framing once the output written so far has left:
    /// the reply to `CONFIG cnc_baud ...` reaches the CNC at the framing it was asked in.
    async fn follow_cnc_framing<B: BridgeEndpoint>(&mut self, bridge: &B) -> TurnResult<(), P, C> {
        let wanted = bridge.cnc_port_config();
        if self.cnc_framing == Some(wanted) {
            return Ok(());
        }
        self.cnc.flush().await.map_err(TurnError::CncWrite)?;
        // Noted before it is tried: a framing the port refuses is reported once, not every turn
        // (the settings only take framings both boards' UARTs run).
        self.cnc_framing = Some(wanted);
        self.cnc
            .set_port_config(wanted)
            .map_err(|UnsupportedConfig| TurnError::CncUnsupported(wanted))
    }

    fn exchange_in<B: BridgeEndpoint>(&mut self, bridge: &mut B) {
        for unit in UnitSet::ALL {
            if let Some((inputs, outputs)) = self.io.take_snapshot(unit) {
                bridge.set_io_snapshot_of(unit.index(), inputs, outputs);
            }
        }
        while let Some((unit, at, event)) = self.io.try_event() {
            bridge.on_io_event_of(unit.index(), at, event);
        }
    }

    /// Drafts to the keeper while it has room (the rest wait in the bridge's bounded queue),
    /// and a `HISTORY` request when none is under way and every draft noted before it has been
    /// handed over, so that the answer shows them (a keeper with no room, as the board's
    /// channel at boot while its history task scans the flash, only delays the request).
    fn exchange_history<B: BridgeEndpoint>(&mut self, bridge: &mut B) {
        while self.history.has_room() {
            let Some(draft) = bridge.take_history_draft() else {
                break;
            };
            self.history.record(draft);
        }
        let drafts_first = self.history.keeps_drafts() && bridge.history_drafts_waiting();
        if !self.reading_history
            && !drafts_first
            && let Some(request) = bridge.take_history_request()
        {
            self.history.start(request);
            self.reading_history = true;
        }
    }

    fn exchange_out<B: BridgeEndpoint>(&mut self, bridge: &B) {
        let count = bridge.unit_count();
        if self.sent_unit_count != Some(count) {
            self.io.send_unit_count(count);
            self.sent_unit_count = Some(count);
        }
        for (unit, sent) in UnitSet::ALL.into_iter().zip(&mut self.sent_supply) {
            let supply = bridge.supply_state_of(unit.index());
            if *sent != Some(supply) {
                self.io.send_supply(unit, supply);
                *sent = Some(supply);
            }
        }
        let config = bridge.io_config();
        if self.sent_io_config != Some(config) {
            self.io.send_io_config(config);
            self.sent_io_config = Some(config);
        }
    }

    async fn drain_cnc<B: BridgeEndpoint, K: Clock>(
        &mut self,
        bridge: &mut B,
        clock: &K,
    ) -> TurnResult<(), P, C> {
        let mut buf = [0u8; CNC_RX_CHUNK];
        while self.cnc.read_ready().map_err(TurnError::CncRead)? {
            let n = read_cnc(&mut self.cnc, &mut buf).await?;
            bridge.handle_cnc_rx(clock.now(), buf.get(..n).unwrap_or(&buf));
        }
        Ok(())
    }

    async fn wait<B, K>(&mut self, bridge: &mut B, clock: &K) -> TurnResult<(), P, C>
    where
        B: BridgeEndpoint,
        V: SettingsSaver<B::Saved, B::SaveError>,
        K: Clock,
    {
        let started = clock.now();
        let latest = started + MAX_WAIT;
        let deadline = bridge.poll_at().map_or(latest, |at| at.min(latest));
        let mut ps_buf = [0u8; PS_RX_CHUNK];
        let mut cnc_buf = [0u8; CNC_RX_CHUNK];
        let (saving, reading_history) = (self.saving, self.reading_history);
        let Supervisor {
            ps,
            cnc,
            io,
            saver,
            history,
            ..
        } = self;
        let save_done = async {
            if saving {
                saver.finished().await
            } else {
                pending().await
            }
        };
        let history_done = async {
            if reading_history {
                history.finished().await
            } else {
                pending().await
            }
        };
        let woke = select6(
            ps.read(&mut ps_buf),
            read_cnc(cnc, &mut cnc_buf),
            io.event_ready(),
            save_done,
            history_done,
            clock.sleep_until(deadline),
        )
        .await;
        let now = clock.now();
        match woke {
            Either6::First(read) => {
                let n = read.map_err(TurnError::Ps)?;
                bridge.handle_ps_rx(now, ps_buf.get(..n).unwrap_or(&ps_buf));
            }
            Either6::Second(read) => {
                let n = read?;
                bridge.handle_cnc_rx(now, cnc_buf.get(..n).unwrap_or(&cnc_buf));
            }
            // Taken at the start of the next turn.
            Either6::Third(()) => {}
            Either6::Fourth(result) => {
                self.saving = false;
                bridge.save_finished(now, result);
            }
            Either6::Fifth(answer) => {
                self.reading_history = false;
                bridge.history_finished(now, &answer);
            }
            Either6::Sixth(()) => {
                if deadline <= started {
                    // The bridge asked to be polled at a time already past and nothing else
                    // happened: let the other tasks run before the next turn.
                    yield_now().await;
                }
            }
        }
        Ok(())
    }
}

async fn read_cnc<C: Read, PE>(
    cnc: &mut C,
    buf: &mut [u8],
) -> core::result::Result<usize, TurnError<PE, C::Error>> {
    match cnc.read(buf).await {
        Ok(0) => Err(TurnError::CncClosed),
        Ok(n) => Ok(n),
        Err(e) => Err(TurnError::CncRead(e)),
    }
}

#[cfg(test)]
mod tests;
