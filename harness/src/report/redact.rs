//! Masks what a device picks anew each run (session handles, connection ids, sequence
//! numbers) in a transcript before it is stored as a snapshot or compared, with the bus's own
//! knowledge of its frames ([`crate::bus::Variable`]). A transcript is a function of the case
//! alone against the embedded simulator; against a device on the network only once masked.
//!
//! A masked byte reads `..`: `  <- 6F 00 14 00 .. .. .. .. 00 00 …`.

use crate::bus::{self, Bus};

/// The transcript with its bus's variable bytes masked (the bus one of `buses`); the bus is the one after `@` in its
/// `profile:` line (a PPO profile has none, and nothing to mask).
pub(crate) fn redact(buses: &[&Bus], text: &str) -> String {
    let variable = text
        .lines()
        .find_map(|l| l.strip_prefix("profile: "))
        .and_then(|p| p.split_once('@'))
        .and_then(|(_, name)| bus::by_name(buses, name))
        .map(|b| b.variable);
    let Some(variable) = variable else {
        return text.to_string();
    };
    let mut out = String::with_capacity(text.len());
    let mut after_frame = false;
    for line in text.split_inclusive('\n') {
        let (body, end) = match line.strip_suffix('\n') {
            Some(b) => (b, "\n"),
            None => (line, ""),
        };
        let frame = body
            .strip_prefix("  -> ")
            .or_else(|| body.strip_prefix("  <- "));
        match (frame, body.strip_prefix("     ")) {
            (Some(hex), _) => {
                out.push_str(&body[..5]);
                out.push_str(&mask(hex, variable));
                after_frame = true;
            }
            (None, Some(decoded)) if after_frame => {
                out.push_str("     ");
                out.push_str(&(variable.decoded)(decoded));
                after_frame = false;
            }
            _ => {
                out.push_str(body);
                after_frame = false;
            }
        }
        out.push_str(end);
    }
    out
}

/// One frame's hex with its variable bytes as `..`; text that is not hex bytes stays.
fn mask(hex: &str, variable: bus::Variable) -> String {
    let Ok(bytes) = hex
        .split_whitespace()
        .map(|b| u8::from_str_radix(b, 16))
        .collect::<Result<Vec<u8>, _>>()
    else {
        return hex.to_string();
    };
    let ranges = (variable.bytes)(&bytes);
    hex.split_whitespace()
        .enumerate()
        .map(|(i, b)| {
            if ranges.iter().any(|r| r.contains(&i)) {
                ".."
            } else {
                b
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    const ENIP: &str = "case: x\nprofile: tu3-eip@enip\n\nstep 1: read\n  -> 65 00 04 00 00 10 00 00 00 00 00 00 01 00 00 00 00 00 00 00 00 00 00 00 01 00 00 00\n     RegisterSession\n  <- 02 00 02 80 08 00 01 00 00 4E 19 00 00 00 B1 00 38 00 19 00 01 00\n     I/O T→O count 25 (50 bytes)\n  <- (nothing received)\n";

    #[test]
    fn two_sessions_with_other_handles_compare_equal() {
        let other = ENIP.replace("65 00 04 00 00 10 00 00", "65 00 04 00 7A 3C 01 9F");
        assert_ne!(other, ENIP);
        assert_eq!(
            redact(crate::buses::BUSES, &other),
            redact(crate::buses::BUSES, ENIP)
        );
        let r = redact(crate::buses::BUSES, ENIP);
        assert!(r.contains("  -> 65 00 04 00 .. .. .. .. 00 00"), "{r}");
        assert!(r.contains("  <- 02 00 02 80 08 00 .. .. .. .. .. .. .. .. B1 00 38 00 .. .. 01 00\n     I/O T→O count .. (50 bytes)\n"), "{r}");
        assert!(r.ends_with("  <- (nothing received)\n"), "{r}");
    }

    #[test]
    fn a_stored_snapshot_masked_once_stays_as_it_is() {
        let once = redact(crate::buses::BUSES, ENIP);
        assert_eq!(redact(crate::buses::BUSES, &once), once);
    }

    #[test]
    fn what_the_device_answers_stays_compared() {
        let changed = ENIP.replace("B1 00 38 00 19 00 01 00", "B1 00 38 00 19 00 02 00");
        assert_ne!(
            redact(crate::buses::BUSES, &changed),
            redact(crate::buses::BUSES, ENIP)
        );
    }

    #[test]
    fn ppo_transcripts_and_buses_without_variable_bytes_are_kept() {
        let ppo = "profile: sk550p\n  -> 65 02 24 4E 01 00 00 00 00 FA\n     AK 2\n";
        assert_eq!(redact(crate::buses::BUSES, ppo), ppo);
        let ecat = ENIP.replace("tu3-eip@enip", "sk550p@ecat");
        assert_eq!(redact(crate::buses::BUSES, &ecat), ecat);
    }
}
