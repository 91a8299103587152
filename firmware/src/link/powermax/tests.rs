//! The Powermax driver's schedule and commands: fault checks between polls, nothing starved, quick
//! restart and gas test.

use std::vec::Vec;

use plasma_protocol::powermax::{FaultCode, OperatingMode, Pressure};
use plasma_protocol::time::{Duration, Instant};

use crate::link::test_support::*;
use crate::link::{
    ActiveFault, CommandOutput, FAULT_CHECK_INTERVAL, LinkCommand, LinkConfig, LinkEvent, Refusal,
};

#[test]
fn a_new_fault_is_reported_within_one_poll_interval() {
    let mut bench = sync_bench();
    bench.events();
    let t0 = bench.now;
    bench.fault(500);
    bench.run(t0 + Duration::from_millis(200));
    let events = bench.events();
    let raised = LinkEvent::FaultRaised {
        code: ActiveFault::Powermax(FaultCode(500)),
        action_required: true,
    };
    assert!(events.contains(&raised));
    assert!(!bench.link.status().ready);
    bench.fault(0);
    bench.run(bench.now + Duration::from_millis(200));
    assert!(bench.events().contains(&LinkEvent::FaultCleared {
        code: ActiveFault::Powermax(FaultCode(500))
    }));
    assert!(bench.link.status().ready);
}

/// The SYNC reads that see the active fault: the status block, and the fault register alone.
fn sync_fault_reads(sent: &[(Instant, Vec<u8>)]) -> (Vec<Instant>, usize, usize) {
    let block = mb(&[0x04, 0x30, 0x10, 0x00, 0x0B]);
    let alone = mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    let at: Vec<Instant> = sent
        .iter()
        .filter(|(_, f)| *f == block || *f == alone)
        .map(|(t, _)| *t)
        .collect();
    let polls = sent.iter().filter(|(_, f)| *f == block).count();
    (at, polls, sent.iter().filter(|(_, f)| *f == alone).count())
}

/// The longest time between two reads of the fault register.
fn longest_gap(at: &[Instant]) -> Duration {
    at.windows(2)
        .map(|w| w[1].saturating_since(w[0]))
        .max()
        .unwrap()
}

#[test]
fn between_two_polls_the_fault_register_is_read_alone() {
    let mut bench = sync_bench();
    let mark = bench.sent.len();
    bench.run(bench.now + Duration::from_millis(2000));
    let (at, polls, alone) = sync_fault_reads(&bench.sent[mark..]);
    // The poll keeps its 100 ms; one short read goes between two polls.
    assert!((19..=21).contains(&polls), "{polls}");
    assert!(alone.abs_diff(polls) <= 1, "{polls} {alone}");
    // Alone never sooner than the interval after the last read of the fault register, and
    // late only by a transaction already on the line (the cartridge check, 8 registers).
    let alone_at: Vec<Instant> = bench.sent[mark..]
        .iter()
        .filter(|(_, f)| *f == mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]))
        .map(|(t, _)| *t)
        .collect();
    for (previous, next) in at.iter().zip(&at[1..]) {
        if alone_at.contains(next) {
            assert!(
                next.saturating_since(*previous) >= FAULT_CHECK_INTERVAL,
                "{at:?}"
            );
        }
    }
    assert!(
        longest_gap(&at) <= FAULT_CHECK_INTERVAL + Duration::from_millis(45),
        "{at:?}"
    );
    // Its answer raises a fault that appeared after the poll's read.
    let block = mb(&[0x04, 0x30, 0x10, 0x00, 0x0B]);
    let alone = mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    bench.run_until_sent(bench.now + Duration::from_millis(200), |f| f == block);
    bench.run(bench.now + Duration::from_millis(50));
    bench.events();
    bench.fault(500);
    let sent = bench.run_until_sent(bench.now + Duration::from_millis(200), |f| {
        f == block || f == alone
    });
    assert_eq!(sent, Some(alone));
    // Request, the unit's 3 ms, the reply: about 21 ms.
    bench.run(bench.now + Duration::from_millis(25));
    assert!(
        bench
            .events()
            .iter()
            .any(|e| matches!(e, LinkEvent::FaultRaised { .. }))
    );
}

#[test]
fn a_stream_of_commands_starves_neither_the_fault_checks_nor_the_slow_data() {
    let mut bench = sync_bench();
    bench.events();
    let counters = bench
        .link
        .submit(bench.now, LinkCommand::RefreshSlowData)
        .unwrap();
    let mark = bench.sent.len();
    let until = bench.now + Duration::from_millis(2000);
    let mut applied = 0;
    let mut counters_done = false;
    while bench.now < until {
        // The queue is kept full.
        while bench
            .link
            .submit(
                bench.now,
                LinkCommand::ApplyProcess {
                    mode: OperatingMode::Cut,
                    current: amps(40 + (applied % 2) as u16 * 5),
                    pressure: Pressure::Auto,
                },
            )
            .is_ok()
        {
            applied += 1;
        }
        bench.run(bench.now + Duration::from_millis(10));
        for event in bench.events() {
            if let LinkEvent::CommandDone { ticket, result } = event
                && ticket == counters
            {
                assert_eq!(result, Ok(CommandOutput::Done));
                counters_done = true;
            }
        }
    }
    assert!(counters_done, "the slow data was read all the same");
    assert!(applied >= 10, "{applied}");
    let (at, polls, _) = sync_fault_reads(&bench.sent[mark..]);
    // A command of two transactions, then the fault register (or a poll, when due).
    assert!(polls >= 10, "{polls}");
    assert!(
        longest_gap(&at) <= FAULT_CHECK_INTERVAL + Duration::from_millis(80),
        "{at:?}"
    );
}

#[test]
fn a_unit_that_refuses_the_fault_register_alone_is_left_to_the_polls() {
    let mut bench = Bench::new(LinkConfig::default());
    bench.next_tx(ms(0)).unwrap();
    bench.rx(20, b":012B0E0481000101010630383133333504\r\n");
    let alone = mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    let mut refused = 0;
    // Every read answered with zeros, but the fault register alone with exception 02.
    while let Some(request) = bench.next_tx(ms(2000)) {
        let text = std::str::from_utf8(&request).unwrap();
        let quantity = u16::from_str_radix(&text[9..13], 16).unwrap();
        let reply = if request == alone {
            refused += 1;
            mb(&[0x84, 0x02])
        } else {
            let mut pdu = std::vec![0x04, (quantity * 2) as u8];
            pdu.resize(2 + usize::from(quantity) * 2, 0);
            mb(&pdu)
        };
        bench.rx(30, &reply);
    }
    assert_eq!(refused, 1);
    let (at, polls, _) = sync_fault_reads(&bench.sent);
    assert!(polls >= 15, "{polls}");
    // Every 100 ms, late by at most one other transaction (30 ms here).
    assert!(
        longest_gap(&at[2..]) <= Duration::from_millis(130),
        "{at:?}"
    );
}

#[test]
fn quick_restart_needs_0_50_0_and_is_followed_by_2_s_of_silence() {
    let mut bench = sync_bench();
    assert_eq!(
        bench.link.submit(bench.now, LinkCommand::QuickRestart),
        Err(Refusal::QuickRestartNeeds050 { active: None })
    );
    bench.fault(121);
    bench.run(bench.now + Duration::from_millis(200));
    assert_eq!(
        bench.link.submit(bench.now, LinkCommand::QuickRestart),
        Err(Refusal::QuickRestartNeeds050 {
            active: Some(FaultCode(121))
        })
    );
    bench.fault(500);
    bench.run(bench.now + Duration::from_millis(200));
    let ticket = bench
        .link
        .submit(bench.now, LinkCommand::QuickRestart)
        .unwrap();
    let limit = bench.now + Duration::from_secs(1);
    let restart = bench
        .run_until_sent(limit, |f| f.starts_with(b":0110308E"))
        .unwrap();
    assert_lrc(b":0110308E0002040404061805\r\n");
    assert_eq!(restart, b":0110308E0002040404061805\r\n");
    // The unit's reply; nothing goes out afterwards (the quiet time).
    bench.run(bench.now + Duration::from_millis(100));
    assert!(bench.heard().ends_with(b":0110308E00022F\r\n"));
    let t_reply = bench.ps().heard.last().unwrap().0;
    assert!(bench.events().contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Done)
    }));
    assert_eq!(
        bench.link.status().restart_blackout_until,
        Some(t_reply + Duration::from_secs(2))
    );
    assert!(!bench.link.status().ready);
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::GasTest { on: true }),
        Err(Refusal::Blackout {
            until: t_reply + Duration::from_secs(2)
        })
    );
    assert_eq!(bench.link.poll_at(), Some(t_reply + Duration::from_secs(2)));
    assert!(
        bench
            .link
            .poll_transmit(t_reply + Duration::from_millis(1999))
            .is_none()
    );
    let next = bench
        .link
        .poll_transmit(t_reply + Duration::from_secs(2))
        .map(|f| f.to_vec());
    assert!(next.is_some(), "traffic resumes after 2 s");
}

#[test]
fn gas_test_writes_the_coil() {
    let mut bench = sync_bench();
    bench
        .link
        .submit(bench.now, LinkCommand::GasTest { on: true })
        .unwrap();
    bench.run(bench.now + Duration::from_millis(200));
    assert_lrc(b":01053180FF004A\r\n");
    assert!(
        bench
            .writes_since(0)
            .iter()
            .any(|w| w == b":01053180FF004A\r\n")
    );
}

/// A legacy unit's torch lead comes from its torch-lead coils, read as slow data: Powermax65/85
/// protocol (001_0bf4bbd6620a48c8.txt) lines 258-271: read 2 coils from 0x0808, the reply's
/// last 2 bits the lead length, `:01010101FC` 35-50 ft.
#[test]
fn a_legacy_units_torch_lead_is_read_from_its_coils() {
    use plasma_protocol::powermax::LeadLength;
    let mut bench = Bench::with_unit(LinkConfig::default(), "pm65");
    bench.ps().powermax().config_mut().torch_id = 0x05;
    bench.run(bench.now + Duration::from_millis(1500));
    assert!(bench.link.status().link_up);
    let read = mb(&[0x01, 0x08, 0x08, 0x00, 0x02]);
    assert!(
        bench.sent.iter().any(|(_, f)| *f == read),
        "the coils were read"
    );
    assert!(bench.heard().windows(13).any(|w| w == b":01010101FC\r\n"));
    assert_eq!(bench.link.status().legacy_lead, Some(LeadLength::Upto15m));
}
