//! The dashboard drawn with ratatui: a full layout from 80x24 up, a compact one below.

use std::time::Duration;

use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Block, Chart, Dataset, Gauge, GraphType, Paragraph, Wrap};

use super::state::{Connection, Consumables, Dashboard, History, PLOT_WINDOW, used_percent};
use crate::history::Row;

/// The smallest area that gets the full layout.
pub const FULL_WIDTH: u16 = 80;
/// See [`FULL_WIDTH`].
pub const FULL_HEIGHT: u16 = 24;

/// The keys, as the screen shows them.
pub const KEYS: &str = "g gas check | r remote off | c clear warnings | q quit";

/// Draws `dash` as at `now` on the whole frame.
pub fn render(frame: &mut Frame, dash: &Dashboard, now: Duration) {
    let area = frame.area();
    if area.width >= FULL_WIDTH && area.height >= FULL_HEIGHT {
        full(frame, dash, now, area);
    } else {
        compact(frame, dash, area);
    }
}

fn full(frame: &mut Frame, dash: &Dashboard, now: Duration, area: Rect) {
    let [top, middle, bottom, keys] = Layout::vertical([
        Constraint::Length(7),
        Constraint::Length(6),
        Constraint::Min(6),
        Constraint::Length(2),
    ])
    .areas(area);
    let [unit, process, lamps] = Layout::horizontal([
        Constraint::Percentage(40),
        Constraint::Percentage(30),
        Constraint::Percentage(30),
    ])
    .areas(top);
    frame.render_widget(
        Paragraph::new(unit_lines(dash))
            .wrap(Wrap { trim: true })
            .block(Block::bordered().title(" Unit and link ")),
        unit,
    );
    frame.render_widget(
        Paragraph::new(process_lines(dash)).block(Block::bordered().title(" Process ")),
        process,
    );
    frame.render_widget(
        Paragraph::new(lamp_lines(dash)).block(Block::bordered().title(" Signals ")),
        lamps,
    );

    let [fault, consumables] =
        Layout::horizontal([Constraint::Percentage(65), Constraint::Percentage(35)]).areas(middle);
    frame.render_widget(
        Paragraph::new(fault_lines(dash))
            .wrap(Wrap { trim: true })
            .block(Block::bordered().title(" Fault ")),
        fault,
    );
    consumables_panel(frame, dash, consumables);

    let [plot, right] =
        Layout::horizontal([Constraint::Percentage(50), Constraint::Percentage(50)]).areas(bottom);
    chart(frame, dash, now, plot);
    // The history's entries (and its border) first; the events take what is left.
    let history_height = (u16::from(super::state::HISTORY_SHOWN) + 2).min(right.height / 2);
    let [history, events] =
        Layout::vertical([Constraint::Length(history_height), Constraint::Min(0)]).areas(right);
    history_panel(frame, dash, history);
    let shown = usize::from(events.height.saturating_sub(2));
    let event_lines: Vec<Line> = dash
        .events
        .iter()
        .rev()
        .take(shown)
        .map(|(at, text)| Line::from(format!("{} {text}", time_of_day(dash, *at))))
        .collect();
    frame.render_widget(
        Paragraph::new(event_lines).block(Block::bordered().title(" Events (newest first) ")),
        events,
    );
    frame.render_widget(Paragraph::new(key_lines(dash)), keys);
}

fn compact(frame: &mut Frame, dash: &Dashboard, area: Rect) {
    let mut lines = unit_lines(dash);
    lines.extend(process_lines(dash).into_iter().take(2));
    lines.push(lamp_row(dash));
    lines.extend(fault_lines(dash).into_iter().take(2));
    lines.extend(key_lines(dash));
    frame.render_widget(Paragraph::new(lines).wrap(Wrap { trim: true }), area);
}

/// A STATUS field; `-` while not connected, as the last reply may no longer hold.
fn field<'a>(dash: &'a Dashboard, key: &str) -> &'a str {
    let live = dash.connection == Connection::Up;
    dash.status
        .as_ref()
        .filter(|_| live)
        .and_then(|s| s.get(key))
        .unwrap_or("-")
}

fn unit_lines(dash: &Dashboard) -> Vec<Line<'static>> {
    let connection = match &dash.connection {
        Connection::Connecting => Span::styled("connecting", Style::new().fg(Color::Yellow)),
        Connection::Up => Span::styled("connected", Style::new().fg(Color::Green)),
        Connection::Lost { .. } => Span::styled(
            "LOST, reconnecting",
            Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
        ),
    };
    let link = field(dash, "link");
    let link_style = match link {
        "UP" => Style::new().fg(Color::Green),
        "DOWN" => Style::new().fg(Color::Red),
        _ => Style::new(),
    };
    let errors = dash
        .errors_per_minute()
        .map_or("-".to_string(), |e| format!("{e:.1}"));
    let mut lines = vec![
        Line::from(vec![Span::raw(format!("{}: ", dash.source)), connection]),
        Line::from(format!(
            "model {}  family {}",
            field(dash, "model"),
            field(dash, "family")
        )),
        Line::from(vec![
            Span::raw("unit link "),
            Span::styled(link.to_string(), link_style),
            Span::raw(format!("  errors/min {errors}")),
        ]),
    ];
    if let Some(framing) = &dash.framing {
        lines.push(Line::from(format!("framing {framing}")));
    }
    // Last, as it may be long (a port's error says what to check) and is cut where it must.
    if let Connection::Lost { reason, .. } = &dash.connection {
        lines.push(Line::from(Span::styled(
            reason.clone(),
            Style::new().fg(Color::Red),
        )));
    }
    lines
}

fn process_lines(dash: &Dashboard) -> Vec<Line<'static>> {
    let mut lines = vec![
        Line::from(format!(
            "set    {} A  {} psi  {}",
            field(dash, "amps"),
            field(dash, "psi"),
            field(dash, "mode")
        )),
        Line::from(format!(
            "actual {} A  {} psi",
            field(dash, "out_amps"),
            field(dash, "out_psi")
        )),
        Line::from(format!("remote {}", field(dash, "remote"))),
    ];
    if let Some(state) = dash.status.as_ref().and_then(|s| s.get("state_name")) {
        lines.push(Line::from(format!("state {state}")));
    }
    if let Some(check) = &dash.gas_check {
        lines.push(gas_check_line(check));
    }
    lines
}

/// The last gas check: `gas PASS 72 psi (60-80)`, other fields (an HPR's per gas) as
/// they came, an error as it came.
fn gas_check_line(reply: &str) -> Line<'static> {
    let Some(fields) = reply.strip_prefix("OK ") else {
        return Line::from(Span::styled(
            format!("gas check {reply}"),
            Style::new().fg(Color::Red),
        ));
    };
    let fields = super::parse::Fields::parse(fields);
    let result = fields.get("result").unwrap_or("-").to_string();
    let style = match result.as_str() {
        "PASS" => Style::new().fg(Color::Green),
        _ => Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
    };
    let rest = match (
        fields.get("measured_psi"),
        fields.get("min_psi"),
        fields.get("max_psi"),
    ) {
        (Some(psi), Some(min), Some(max)) => format!(" {psi} psi ({min}-{max})"),
        _ => fields
            .iter()
            .filter(|(k, v)| !v.is_empty() && *k != "result")
            .map(|(k, v)| format!(" {k}={v}"))
            .collect(),
    };
    Line::from(vec![
        Span::raw("gas "),
        Span::styled(result, style),
        Span::raw(rest),
    ])
}

fn lamp(name: &str, on: Option<bool>, on_color: Color) -> Span<'static> {
    let (mark, style) = match on {
        Some(true) => ("●", Style::new().fg(on_color).add_modifier(Modifier::BOLD)),
        Some(false) => ("○", Style::new().fg(Color::DarkGray)),
        None => ("?", Style::new().fg(Color::DarkGray)),
    };
    Span::styled(format!("{mark} {name}  "), style)
}

/// The lamps, unknown (`?`) without a fresh STATUS over a live connection.
fn lamps(dash: &Dashboard) -> [Span<'static>; 5] {
    let known = dash.connection == Connection::Up && dash.status.is_some();
    let on = |key: &str| known.then(|| field(dash, key) == "ON");
    let fault = known.then(|| field(dash, "fault") != "none");
    [
        lamp("START", on("start"), Color::Green),
        lamp("ARC_OK", on("arc_ok"), Color::Green),
        lamp("READY", on("ready"), Color::Green),
        lamp("FAULT", fault, Color::Red),
        lamp("MOTION", on("motion"), Color::Green),
    ]
}

fn lamp_lines(dash: &Dashboard) -> Vec<Line<'static>> {
    let [start, arc_ok, ready, fault, motion] = lamps(dash);
    vec![
        Line::from(vec![start, arc_ok]),
        Line::from(vec![ready, fault]),
        Line::from(vec![motion]),
    ]
}

fn lamp_row(dash: &Dashboard) -> Line<'static> {
    Line::from(Vec::from(lamps(dash)))
}

fn fault_lines(dash: &Dashboard) -> Vec<Line<'static>> {
    if dash.connection != Connection::Up {
        return vec![Line::from("unknown: not connected")];
    }
    match &dash.fault {
        None if dash.status.is_some() => vec![Line::from("no fault")],
        None => vec![Line::from("-")],
        Some(fault) => {
            let steps = match fault.action.as_str() {
                "required" => "steps required",
                "recommended" => "steps recommended",
                "none" => "no steps needed",
                _ => "steps: asking",
            };
            vec![
                Line::from(Span::styled(
                    format!("FAULT {} ({steps})", fault.code),
                    Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
                )),
                Line::from(fault.text.clone()),
            ]
        }
    }
}

fn consumables_panel(frame: &mut Frame, dash: &Dashboard, area: Rect) {
    let block = Block::bordered().title(" Consumables ");
    match &dash.consumables {
        Consumables::Unknown => frame.render_widget(Paragraph::new("-").block(block), area),
        Consumables::NotReported => frame.render_widget(
            Paragraph::new("not reported by this bridge")
                .wrap(Wrap { trim: true })
                .block(block),
            area,
        ),
        Consumables::Reported(fields) => {
            let inner = block.inner(area);
            frame.render_widget(block, area);
            let [counts, bar, warning] = Layout::vertical([
                Constraint::Length(1),
                Constraint::Length(1),
                Constraint::Min(0),
            ])
            .areas(inner);
            let value = |key: &str| fields.get(key).unwrap_or("-").to_string();
            frame.render_widget(
                Paragraph::new(format!(
                    "starts {}  arc {} s  {}",
                    value("starts"),
                    value("arc_s"),
                    value("source")
                )),
                counts,
            );
            match used_percent(fields) {
                Some(percent) => frame.render_widget(
                    Gauge::default()
                        .gauge_style(Style::new().fg(if percent >= 90.0 {
                            Color::Red
                        } else {
                            Color::Green
                        }))
                        .ratio((percent / 100.0).clamp(0.0, 1.0))
                        .label(format!("{percent:.0} % used")),
                    bar,
                ),
                None => frame.render_widget(Paragraph::new("no limit set (used=OFF)"), bar),
            }
            if let Some(text) = &dash.consumable_warning {
                frame.render_widget(
                    Paragraph::new(Span::styled(
                        text.clone(),
                        Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
                    ))
                    .wrap(Wrap { trim: true }),
                    warning,
                );
            }
        }
    }
}

fn history_panel(frame: &mut Frame, dash: &Dashboard, area: Rect) {
    let block = Block::bordered().title(" History (bridge, newest first) ");
    let lines: Vec<Line> = match &dash.history {
        History::Unknown => vec![Line::from("-")],
        History::NotReported(reply) => vec![Line::from(format!("not available: {reply}"))],
        History::Entries(rows) if rows.is_empty() => vec![Line::from("no entries")],
        History::Entries(rows) => rows.iter().map(history_line).collect(),
    };
    frame.render_widget(Paragraph::new(lines).block(block), area);
}

/// An entry in one line: when (`11-26 07:30`, or the boot and the seconds since it), what,
/// details. The minute is enough to tell last night from this morning; the order is the
/// bridge's.
fn history_line(row: &Row) -> Line<'static> {
    let clock = row.get("clock");
    let when = match clock.get(5..16).map(|rest| rest.replacen('T', " ", 1)) {
        Some(month_to_minute) if clock != "-" => month_to_minute,
        _ => format!(
            "boot {} +{} s",
            row.get("boot"),
            row.get("uptime_ms")
                .parse::<u64>()
                .map_or(0, |ms| ms / 1000)
        ),
    };
    let event = row.get("event").to_string();
    let style = match event.as_str() {
        "FAULT" | "LINK_LOST" | "START_REFUSED" | "DROPPED" => Style::new().fg(Color::Red),
        _ => Style::new(),
    };
    // The unit, beyond the first, as every other line about it says it.
    let unit = match row.cell("unit") {
        "1" => String::new(),
        n => format!(" unit={n}"),
    };
    Line::from(vec![
        Span::raw(format!("{when} ")),
        Span::styled(event, style),
        Span::raw(format!(" {}{unit}", row.details())),
    ])
}

fn chart(frame: &mut Frame, dash: &Dashboard, now: Duration, area: Rect) {
    let ago = |at: Duration| -(now.saturating_sub(at).as_secs_f64());
    let amps: Vec<(f64, f64)> = dash
        .samples
        .iter()
        .filter_map(|s| Some((ago(s.at), s.amps?)))
        .collect();
    let psi: Vec<(f64, f64)> = dash
        .samples
        .iter()
        .filter_map(|s| Some((ago(s.at), s.psi?)))
        .collect();
    let top = amps
        .iter()
        .chain(&psi)
        .map(|&(_, v)| v)
        .fold(10.0_f64, f64::max)
        .ceil();
    let window = PLOT_WINDOW.as_secs_f64();
    let datasets = vec![
        Dataset::default()
            .name("out_amps")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::new().fg(Color::Yellow))
            .data(&amps),
        Dataset::default()
            .name("out_psi")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::new().fg(Color::Cyan))
            .data(&psi),
    ];
    let chart = Chart::new(datasets)
        // The colours say which line is which: a legend box would hide the newest points.
        .block(Block::bordered().title(Line::from(vec![
            Span::raw(" Actual "),
            Span::styled("current A", Style::new().fg(Color::Yellow)),
            Span::raw(" and "),
            Span::styled("pressure psi", Style::new().fg(Color::Cyan)),
            Span::raw(" "),
        ])))
        .hidden_legend_constraints((Constraint::Length(0), Constraint::Length(0)))
        .x_axis(
            Axis::default()
                .bounds([-window, 0.0])
                .labels([format!("-{:.0} min", window / 60.0), "now".to_string()]),
        )
        .y_axis(
            Axis::default()
                .bounds([0.0, top])
                .labels(["0".to_string(), format!("{top:.0}")]),
        );
    frame.render_widget(chart, area);
}

fn key_lines(dash: &Dashboard) -> Vec<Line<'static>> {
    let mut lines = vec![Line::from(Span::styled(
        KEYS,
        Style::new().add_modifier(Modifier::REVERSED),
    ))];
    if let Some(action) = &dash.last_action {
        lines.push(Line::from(action.clone()));
    }
    lines
}

/// `HH:MM:SS` (UTC) of a time since the monitor started.
fn time_of_day(dash: &Dashboard, at: Duration) -> String {
    let seconds = (dash.wall_origin_s + at.as_secs()) % 86_400;
    format!(
        "{:02}:{:02}:{:02}",
        seconds / 3600,
        seconds / 60 % 60,
        seconds % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(line: &Line<'_>) -> String {
        line.spans.iter().map(|s| s.content.as_ref()).collect()
    }

    #[test]
    fn a_history_line_names_its_unit_beyond_the_first() {
        // As the bridge writes them (docs/cnc-protocol.md, HISTORY).
        let second = Row::parse(
            "HISTORY seq=0 boot=0 uptime_ms=3313 clock=- family=HPR model=HPR260 event=FAULT \
             code=044 action=required unit=2",
        )
        .unwrap();
        assert_eq!(
            text(&history_line(&second)),
            "boot 0 +3 s FAULT code=044 action=required unit=2"
        );
        let first = Row::parse(
            "HISTORY seq=1 boot=0 uptime_ms=4313 clock=- family=HPR model=HPR260 event=FAULT \
             code=044 action=required",
        )
        .unwrap();
        assert_eq!(
            text(&history_line(&first)),
            "boot 0 +4 s FAULT code=044 action=required"
        );
    }
}
