//! `harness serve <bus> --misbehave SPEC`: a served device that misbehaves on purpose, so that
//! a test can show the harness's master, scanner or controller names what the device did
//! (a working counter of 0, no PRes for three cycles, a general status 08h) rather than
//! hanging, panicking or blaming its own host.
//!
//! The spec is modes separated by commas, each at most once (`docs/misbehave.md`):
//! `late=500ms`, `late=100ms..900ms`, `drop=20%`, `drop=every:3`, `dup`, `dup=every:2`,
//! `reorder`, `silent=2s`, `silent=2s@5s`, `corrupt=FIELD`, `close`, `alarm=2s`,
//! `alarm=every:2s`. The random choices
//! (a jittered delay, `drop=20%`) come from `--seed`, so that one spec and seed make the same
//! run twice. What a mode does per bus is the driver's ([`super::inject`]) and the bus's
//! (which answers are held late, which fields it can corrupt).

use std::fmt;
use std::num::NonZeroU32;
use std::str::FromStr;
use std::time::Duration;

/// The default `--seed`: fixed, so that runs repeat unless a seed is given.
pub(crate) const DEFAULT_SEED: u64 = 0x4E4F_5244;

/// Which of the frames a mode applies to touches it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pick {
    /// Every one.
    All,
    /// Each with this chance, in percent (1…100), drawn from the seed.
    Percent(u8),
    /// The n-th, 2n-th… (`every:n`).
    Every(NonZeroU32),
}

/// How late a held answer leaves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Late {
    /// The least delay.
    pub min: Duration,
    /// The most (equal to `min`: a fixed delay; else drawn between them from the seed).
    pub max: Duration,
}

/// When the device goes silent, and for how long.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Silent {
    /// How long nothing leaves.
    pub length: Duration,
    /// When the silence starts, from the start of serving (`None`: at the first input the
    /// device is handed, the first exchange).
    pub at: Option<Duration>,
}

/// When the device raises spurious alarms or emergencies (`alarm=`), from its first exchange.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Alarm {
    /// After the first exchange, and between two when it repeats.
    pub after: Duration,
    /// `every:`: again and again; else once.
    pub repeat: bool,
}

/// A field the device can send wrong (`corrupt=FIELD`); each bus says which it has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// EtherCAT: every datagram's working counter 0.
    Wkc,
    /// EtherCAT: the frame header's length past the frame's end.
    Length,
    /// POWERLINK: the PRes NMT status a state the node is not in (STOPPED).
    State,
    /// PROFINET IO: the input CR's cycle counter stands still.
    Cycle,
    /// PROFINET IO: the input CR's data status says the data is not valid.
    DataStatus,
    /// A status code of the answers bad (EtherNet/IP: the CIP general status of explicit
    /// replies 08h, service not supported).
    Status,
    /// A sequence number wrong.
    Sequence,
}

impl Field {
    const ALL: [Field; 7] = [
        Field::Wkc,
        Field::Length,
        Field::State,
        Field::Cycle,
        Field::DataStatus,
        Field::Status,
        Field::Sequence,
    ];

    /// Its name in a spec.
    pub fn name(self) -> &'static str {
        match self {
            Field::Wkc => "wkc",
            Field::Length => "length",
            Field::State => "state",
            Field::Cycle => "cycle",
            Field::DataStatus => "data-status",
            Field::Status => "status",
            Field::Sequence => "sequence",
        }
    }
}

/// What a served device does wrong on purpose (`--misbehave SPEC --seed N`); the default does
/// nothing wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Misbehaviour {
    /// `late=`: the answers the bus holds back leave this late.
    pub late: Option<Late>,
    /// `drop=`: frames that never leave.
    pub drop: Option<Pick>,
    /// `dup`: frames that leave twice.
    pub dup: Option<Pick>,
    /// `reorder`: frames that leave after the next one.
    pub reorder: Option<Pick>,
    /// `silent=`: a stretch in which nothing leaves.
    pub silent: Option<Silent>,
    /// `corrupt=`: a field sent wrong, in every frame that has it.
    pub corrupt: Option<Field>,
    /// `close`: sessions closed mid-exchange (EtherNet/IP's TCP; refused on raw buses).
    pub close: bool,
    /// `alarm=`: spurious alarms or emergencies.
    pub alarm: Option<Alarm>,
    /// `--seed`: where the random choices come from.
    pub seed: u64,
}

impl Default for Misbehaviour {
    fn default() -> Misbehaviour {
        Misbehaviour {
            late: None,
            drop: None,
            dup: None,
            reorder: None,
            silent: None,
            corrupt: None,
            close: false,
            alarm: None,
            seed: DEFAULT_SEED,
        }
    }
}

/// What a misbehaving device did, counted per mode (the serve summary).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Touched {
    /// Answers sent late.
    pub late: u64,
    /// Outputs dropped by `drop`.
    pub dropped: u64,
    /// Outputs sent twice.
    pub duplicated: u64,
    /// Outputs sent after the next one.
    pub reordered: u64,
    /// Outputs not sent during a silence.
    pub silenced: u64,
    /// Outputs with a field corrupted.
    pub corrupted: u64,
    /// Sessions closed on purpose.
    pub closed: u64,
    /// Spurious alarms or emergencies raised.
    pub alarms: u64,
}

impl fmt::Display for Touched {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let all = [
            ("late", self.late),
            ("dropped", self.dropped),
            ("duplicated", self.duplicated),
            ("reordered", self.reordered),
            ("silenced", self.silenced),
            ("corrupted", self.corrupted),
            ("closed", self.closed),
            ("alarms raised", self.alarms),
        ];
        let parts: Vec<String> = all
            .iter()
            .filter(|(_, n)| *n > 0)
            .map(|(what, n)| format!("{n} {what}"))
            .collect();
        if parts.is_empty() {
            f.write_str("no frame touched")
        } else {
            f.write_str(&parts.join(", "))
        }
    }
}

/// A spec that does not parse: the part at fault and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{part}`: {why}")]
pub struct SpecError {
    /// The mode as written.
    pub part: String,
    /// What is wrong with it.
    pub why: String,
}

/// What a bus can do of a spec: the fields it can corrupt and whether it has sessions to
/// close.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BusFaults {
    /// The bus's name in messages.
    pub(crate) bus: &'static str,
    /// The fields `corrupt=` takes on it.
    pub(crate) fields: &'static [Field],
    /// Why `close` means nothing on it (`None`: it has sessions and closes them).
    pub(crate) no_close: Option<&'static str>,
    /// Why `alarm=` means nothing on it (`None`: its device raises alarms or emergencies).
    pub(crate) no_alarm: Option<&'static str>,
}

impl Misbehaviour {
    /// A fixed delay on the answers (what `--reply-delay` was).
    pub fn late(delay: Duration) -> Misbehaviour {
        Misbehaviour {
            late: Some(Late {
                min: delay,
                max: delay,
            }),
            ..Misbehaviour::default()
        }
    }

    /// Whether it does anything wrong at all.
    pub fn is_none(&self) -> bool {
        *self
            == Misbehaviour {
                seed: self.seed,
                ..Misbehaviour::default()
            }
    }

    /// This spec with `seed`.
    pub fn with_seed(self, seed: u64) -> Misbehaviour {
        Misbehaviour { seed, ..self }
    }

    /// Refuses what `bus` cannot do, naming the mode and what the bus can.
    pub(crate) fn check(&self, bus: &BusFaults) -> Result<(), SpecError> {
        if let Some(f) = self.corrupt {
            if !bus.fields.contains(&f) {
                let names: Vec<&str> = bus.fields.iter().map(|f| f.name()).collect();
                return Err(SpecError {
                    part: format!("corrupt={}", f.name()),
                    why: format!(
                        "{} has no such field (its fields: {})",
                        bus.bus,
                        names.join(", ")
                    ),
                });
            }
        }
        if let (true, Some(why)) = (self.close, bus.no_close) {
            return Err(SpecError {
                part: "close".into(),
                why: format!("{} {why}", bus.bus),
            });
        }
        match (self.alarm, bus.no_alarm) {
            (Some(a), Some(why)) => Err(SpecError {
                part: alarm_spec(a),
                why: format!("{} {why}", bus.bus),
            }),
            _ => Ok(()),
        }
    }
}

impl FromStr for Misbehaviour {
    type Err = SpecError;

    fn from_str(spec: &str) -> Result<Misbehaviour, SpecError> {
        let mut m = Misbehaviour::default();
        if spec.trim().is_empty() {
            return Err(SpecError {
                part: spec.into(),
                why: "an empty spec; give modes like `late=500ms,drop=20%`".into(),
            });
        }
        let mut seen: Vec<&str> = Vec::new();
        for part in spec.split(',').map(str::trim) {
            let (mode, value) = match part.split_once('=') {
                Some((k, v)) => (k.trim(), Some(v.trim())),
                None => (part, None),
            };
            let err = |why: String| SpecError {
                part: part.into(),
                why,
            };
            if seen.contains(&mode) {
                return Err(err(format!("`{mode}` is given twice")));
            }
            seen.push(mode);
            match (mode, value) {
                ("late", Some(v)) => m.late = Some(late(v).map_err(err)?),
                ("drop", Some(v)) => m.drop = Some(pick(v).map_err(err)?),
                ("dup", v) => m.dup = Some(v.map_or(Ok(Pick::All), pick).map_err(err)?),
                ("reorder", v) => m.reorder = Some(v.map_or(Ok(Pick::All), pick).map_err(err)?),
                ("silent", Some(v)) => m.silent = Some(silent(v).map_err(err)?),
                ("corrupt", Some(v)) => m.corrupt = Some(field(v).map_err(err)?),
                ("close", None) => m.close = true,
                ("close", Some(_)) => return Err(err("`close` takes no value".into())),
                ("alarm", Some(v)) => m.alarm = Some(alarm(v).map_err(err)?),
                ("late" | "drop" | "silent" | "corrupt" | "alarm", None) => {
                    return Err(err(format!(
                        "`{mode}` needs a value, e.g. {}",
                        example(mode)
                    )))
                }
                _ => return Err(err(
                    "unknown mode (modes: late, drop, dup, reorder, silent, corrupt, close, alarm)"
                        .into(),
                )),
            }
        }
        Ok(m)
    }
}

fn example(mode: &str) -> &'static str {
    match mode {
        "late" => "late=500ms or late=100ms..900ms",
        "drop" => "drop=20% or drop=every:3",
        "silent" => "silent=2s or silent=2s@5s",
        "alarm" => "alarm=2s or alarm=every:2s",
        _ => "corrupt=wkc",
    }
}

/// A duration with its unit (`500ms`, `2s`).
fn duration(v: &str) -> Result<Duration, String> {
    if !v.is_empty() && v.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("`{v}` needs a unit, e.g. {v}ms"));
    }
    humantime::parse_duration(v).map_err(|e| format!("`{v}` is not a duration like 500ms: {e}"))
}

fn late(v: &str) -> Result<Late, String> {
    let (min, max) = match v.split_once("..") {
        Some((a, b)) => (duration(a)?, duration(b)?),
        None => (duration(v)?, duration(v)?),
    };
    if min > max {
        return Err(format!("the range `{v}` runs backwards"));
    }
    if max.is_zero() {
        return Err("a delay of 0 is no delay".into());
    }
    Ok(Late { min, max })
}

fn pick(v: &str) -> Result<Pick, String> {
    if let Some(p) = v.strip_suffix('%') {
        return match p.parse::<u8>() {
            Ok(n @ 1..=100) => Ok(Pick::Percent(n)),
            _ => Err(format!("`{v}` is not a percentage 1%…100%")),
        };
    }
    if let Some(n) = v.strip_prefix("every:") {
        return n
            .parse::<NonZeroU32>()
            .map(Pick::Every)
            .map_err(|_| format!("`{n}` is not a count 1 or more"));
    }
    Err(format!("`{v}` is neither a percentage (20%) nor every:N"))
}

fn silent(v: &str) -> Result<Silent, String> {
    let (length, at) = match v.split_once('@') {
        Some((l, a)) => (duration(l)?, Some(duration(a)?)),
        None => (duration(v)?, None),
    };
    if length.is_zero() {
        return Err("a silence of 0 is none".into());
    }
    Ok(Silent { length, at })
}

fn alarm(v: &str) -> Result<Alarm, String> {
    let (after, repeat) = match v.strip_prefix("every:") {
        Some(d) => (duration(d)?, true),
        None => (duration(v)?, false),
    };
    if after.is_zero() && repeat {
        return Err("alarms every 0 s would be endless".into());
    }
    Ok(Alarm { after, repeat })
}

/// `alarm=` as a spec writes it.
fn alarm_spec(a: Alarm) -> String {
    let every = if a.repeat { "every:" } else { "" };
    format!("alarm={every}{}", humantime::format_duration(a.after))
}

fn field(v: &str) -> Result<Field, String> {
    Field::ALL
        .into_iter()
        .find(|f| f.name() == v)
        .ok_or_else(|| {
            let names: Vec<&str> = Field::ALL.iter().map(|f| f.name()).collect();
            format!("unknown field (fields: {})", names.join(", "))
        })
}

impl fmt::Display for Pick {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Pick::All => f.write_str("every frame"),
            Pick::Percent(p) => write!(f, "{p}%"),
            Pick::Every(n) => write!(f, "every:{n}"),
        }
    }
}

impl fmt::Display for Misbehaviour {
    /// The spec as `--misbehave` takes it (modes in a fixed order), and the seed.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = |d: Duration| humantime::format_duration(d).to_string();
        let pick = |p: Pick| match p {
            Pick::All => String::new(),
            p => format!("={p}"),
        };
        let mut parts = Vec::new();
        if let Some(l) = self.late {
            parts.push(if l.min == l.max {
                format!("late={}", d(l.min))
            } else {
                format!("late={}..{}", d(l.min), d(l.max))
            });
        }
        if let Some(p) = self.drop {
            parts.push(format!("drop{}", pick(p)));
        }
        if let Some(p) = self.dup {
            parts.push(format!("dup{}", pick(p)));
        }
        if let Some(p) = self.reorder {
            parts.push(format!("reorder{}", pick(p)));
        }
        if let Some(s) = self.silent {
            let at = s.at.map(|a| format!("@{}", d(a))).unwrap_or_default();
            parts.push(format!("silent={}{at}", d(s.length)));
        }
        if let Some(c) = self.corrupt {
            parts.push(format!("corrupt={}", c.name()));
        }
        if self.close {
            parts.push("close".into());
        }
        if let Some(a) = self.alarm {
            parts.push(alarm_spec(a));
        }
        write!(f, "{} (seed {})", parts.join(","), self.seed)
    }
}

/// The line `harness serve` prints at its start when the device misbehaves on purpose.
pub(crate) fn announce(m: &Misbehaviour) {
    if !m.is_none() {
        outln!("misbehaving on purpose: {m}; each touched frame is a line on stderr");
    }
}

/// The serve summary's line of what the misbehaviour touched, when there was one.
pub(crate) fn summarize(m: &Misbehaviour, t: Touched) {
    if !m.is_none() {
        outln!("misbehaved: {t}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Misbehaviour, String> {
        s.parse::<Misbehaviour>().map_err(|e| e.to_string())
    }

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn every_mode_parses_and_modes_combine() {
        let m = parse("late=100ms..900ms, drop=20%,dup=every:2,reorder,silent=2s@5s,corrupt=wkc")
            .unwrap();
        assert_eq!(
            m.late,
            Some(Late {
                min: ms(100),
                max: ms(900)
            })
        );
        assert_eq!(m.drop, Some(Pick::Percent(20)));
        assert_eq!(m.dup, Some(Pick::Every(NonZeroU32::new(2).unwrap())));
        assert_eq!(m.reorder, Some(Pick::All));
        assert_eq!(
            m.silent,
            Some(Silent {
                length: ms(2000),
                at: Some(ms(5000))
            })
        );
        assert_eq!(m.corrupt, Some(Field::Wkc));
        assert!(!m.close && !m.is_none());
        assert_eq!(parse("late=500ms").unwrap(), Misbehaviour::late(ms(500)));
        assert_eq!(
            parse("silent=2s").unwrap().silent,
            Some(Silent {
                length: ms(2000),
                at: None
            })
        );
        assert!(parse("close").unwrap().close);
        assert_eq!(
            parse("drop=every:3").unwrap().drop,
            Some(Pick::Every(NonZeroU32::new(3).unwrap()))
        );
        assert_eq!(
            parse("corrupt=data-status").unwrap().corrupt,
            Some(Field::DataStatus)
        );
        assert!(Misbehaviour::default().with_seed(7).is_none());
    }

    #[test]
    fn a_spec_prints_as_it_parses() {
        for spec in [
            "late=100ms..900ms,drop=20%,dup,reorder=every:2,silent=2s@5s,corrupt=wkc,close",
            "late=500ms,drop=every:3,silent=1s,alarm=every:2s",
            "corrupt=sequence,alarm=1s 500ms",
        ] {
            let m = parse(spec).unwrap().with_seed(9);
            assert_eq!(m.to_string(), format!("{spec} (seed 9)"));
            assert_eq!(parse(spec).unwrap().with_seed(9), m);
        }
    }

    #[test]
    fn a_bad_spec_names_the_bad_part() {
        for (spec, want) in [
            ("", "``: an empty spec; give modes like `late=500ms,drop=20%`"),
            ("late=500", "`late=500`: `500` needs a unit, e.g. 500ms"),
            ("late=900ms..100ms", "`late=900ms..100ms`: the range `900ms..100ms` runs backwards"),
            ("late=0ms", "`late=0ms`: a delay of 0 is no delay"),
            ("drop=120%", "`drop=120%`: `120%` is not a percentage 1%…100%"),
            ("drop=0%", "`drop=0%`: `0%` is not a percentage 1%…100%"),
            ("drop=every:0", "`drop=every:0`: `0` is not a count 1 or more"),
            ("drop=some", "`drop=some`: `some` is neither a percentage (20%) nor every:N"),
            ("drop", "`drop`: `drop` needs a value, e.g. drop=20% or drop=every:3"),
            ("late=1s,late=2s", "`late=2s`: `late` is given twice"),
            ("close=now", "`close=now`: `close` takes no value"),
            ("silent=0s", "`silent=0s`: a silence of 0 is none"),
            ("alarm", "`alarm`: `alarm` needs a value, e.g. alarm=2s or alarm=every:2s"),
            ("alarm=every:0s", "`alarm=every:0s`: alarms every 0 s would be endless"),
            ("alarm=every:2", "`alarm=every:2`: `2` needs a unit, e.g. 2ms"),
            (
                "corrupt=crc",
                "`corrupt=crc`: unknown field (fields: wkc, length, state, cycle, data-status, status, sequence)",
            ),
            (
                "late=1s,explode",
                "`explode`: unknown mode (modes: late, drop, dup, reorder, silent, corrupt, close, alarm)",
            ),
        ] {
            assert_eq!(parse(spec).unwrap_err(), want, "{spec}");
        }
        assert!(parse("late=soon")
            .unwrap_err()
            .starts_with("`late=soon`: `soon` is not a duration"));
    }

    #[test]
    fn a_bus_refuses_what_it_cannot_do() {
        let ecat = BusFaults {
            bus: "EtherCAT",
            fields: &[Field::Wkc, Field::Length],
            no_close: Some("has no session to close (raw Ethernet): use silent= or drop="),
            no_alarm: None,
        };
        let enip = BusFaults {
            bus: "EtherNet/IP",
            fields: &[Field::Status],
            no_close: None,
            no_alarm: Some("sends nothing unasked"),
        };
        assert!(parse("corrupt=wkc,drop=5%").unwrap().check(&ecat).is_ok());
        assert_eq!(
            parse("corrupt=state")
                .unwrap()
                .check(&ecat)
                .unwrap_err()
                .to_string(),
            "`corrupt=state`: EtherCAT has no such field (its fields: wkc, length)"
        );
        assert_eq!(
            parse("close")
                .unwrap()
                .check(&ecat)
                .unwrap_err()
                .to_string(),
            "`close`: EtherCAT has no session to close (raw Ethernet): use silent= or drop="
        );
        assert!(parse("alarm=every:2s").unwrap().check(&ecat).is_ok());
        assert_eq!(
            parse("alarm=every:2s")
                .unwrap()
                .check(&enip)
                .unwrap_err()
                .to_string(),
            "`alarm=every:2s`: EtherNet/IP sends nothing unasked"
        );
        assert_eq!(
            parse("alarm=every:2s,corrupt=sequence").unwrap().alarm,
            Some(Alarm {
                after: ms(2000),
                repeat: true
            })
        );
    }
}
