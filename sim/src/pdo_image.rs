//! One inverter node's side of the synchronous process data (CiA 301 transmission type 1, the
//! layout of `proto::nord::can::pdo_words`): the control word and setpoints its RPDOs brought
//! last, taken by the drive at each SYNC, answered by its TPDOs.
//!
//! It sits apart from `crate::can` for the reason `crate::sdo_server` does: two owners have an
//! inverter's node, each node of a `crate::can::Segment` and the bus interface's gateway
//! (`crate::system_bus`), which reaches the nodes behind a field-bus device without a whole
//! segment. One image, so that an inverter takes its process data on the system bus behind a
//! field bus exactly as it takes them from a CANopen master on the segment. What is the node's
//! own (its NMT state: PDOs only in Operational; the EMCY a length error gives) stays with the
//! owner.
//!
//! The words of a PDO are read back from its bytes ([`read_words`]) on both sides: by the node
//! from an RPDO, by the gateway from a TPDO.

use proto::can::CanFrame;
use proto::canopen::cob_id::Function;
use proto::nord::can::{pdo_data, pdo_words, process_values, InverterSeries};

/// How a PDO's bytes were read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Read {
    /// As long as its mapping.
    Exact,
    /// Longer than its mapping: processed, the excess ignored (CiA 301 "PDO length exceeded",
    /// EMCY 8220h from a node).
    Longer,
}

/// Why a PDO's bytes were not read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub(crate) enum PdoError {
    /// The PDO carries no words of this series (PDO 3/4, PDO 2 of an inverter with three
    /// values).
    #[error("the PDO carries no process data")]
    NotMapped,
    /// Fewer bytes than its mapping: not processed (CiA 301 "PDO not processed due to length
    /// error", EMCY 8210h from a node).
    #[error("the PDO is shorter than its mapping")]
    TooShort,
}

/// The words PDO `function` of an inverter of `series` carries, read from `data` into their
/// places in `words` (control/status word and values 1…5), UNSIGNED16 little-endian.
pub(crate) fn read_words(
    function: Function,
    series: InverterSeries,
    data: &[u8],
    words: &mut [u16; 6],
) -> Result<Read, PdoError> {
    let (first, count) = pdo_words(function, series).ok_or(PdoError::NotMapped)?;
    let (first, count) = (usize::from(first), usize::from(count));
    if data.len() < 2 * count {
        return Err(PdoError::TooShort);
    }
    for (w, b) in words[first..first + count]
        .iter_mut()
        .zip(data.chunks_exact(2))
    {
        *w = u16::from_le_bytes([b[0], b[1]]);
    }
    Ok(match data.len() > 2 * count {
        true => Read::Longer,
        false => Read::Exact,
    })
}

/// The node's process image.
#[derive(Debug, Clone)]
pub(crate) struct PdoImage {
    /// Its inverter's series: how many process values its PDOs carry.
    series: InverterSeries,
    /// The control word and setpoints 1–5 as the RPDOs last brought them, taken at each SYNC
    /// once an RPDO1 came (`started`).
    outputs: [u16; 6],
    started: bool,
}

impl PdoImage {
    pub(crate) fn new(series: InverterSeries) -> PdoImage {
        PdoImage {
            series,
            outputs: [0; 6],
            started: false,
        }
    }

    /// RPDO `function`'s `data` came (the owner has checked that the node takes PDOs): its
    /// words are kept for the next SYNC; an RPDO1 starts the process data.
    pub(crate) fn receive(&mut self, function: Function, data: &[u8]) -> Result<Read, PdoError> {
        let read = read_words(function, self.series, data, &mut self.outputs)?;
        self.started |= function == Function::Rpdo { number: 1 };
        Ok(read)
    }

    /// The node left Operational: the process data start again with an RPDO1.
    pub(crate) fn stop(&mut self) {
        self.started = false;
    }

    /// SYNC (the owner has checked that the node takes PDOs): once the process data started,
    /// `drive` takes the control word and setpoints the RPDOs brought and gives the status word
    /// and actual values, which node `node` answers as its TPDOs; nothing before, or when the
    /// drive gives nothing.
    pub(crate) fn sync(
        &self,
        node: u8,
        drive: impl FnOnce(u16, &[u16]) -> Option<[u16; 6]>,
    ) -> Vec<CanFrame> {
        if !self.started {
            return Vec::new();
        }
        let values = usize::from(process_values(self.series));
        let [control, setpoints @ ..] = self.outputs;
        let Some(answer) = drive(control, &setpoints[..values]) else {
            return Vec::new();
        };
        [1, 2]
            .into_iter()
            .filter_map(|number| {
                let tpdo = Function::Tpdo { number };
                let data = pdo_data(tpdo, self.series, &answer)?;
                CanFrame::new(tpdo.cob_id(node).ok()?, &data).ok()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RPDO1: Function = Function::Rpdo { number: 1 };
    const RPDO2: Function = Function::Rpdo { number: 2 };

    #[test]
    fn rpdos_are_taken_at_sync_once_an_rpdo1_came() {
        let mut image = PdoImage::new(InverterSeries::Sk54xe);
        let taken = std::cell::RefCell::new(Vec::new());
        let drive = |c: u16, s: &[u16]| {
            taken.borrow_mut().push((c, s.to_vec()));
            Some([0x0B37, 1, 2, 3, 4, 5])
        };
        // An RPDO2 alone does not start the process data.
        assert_eq!(image.receive(RPDO2, &[9, 0, 8, 0]), Ok(Read::Exact));
        assert!(image.sync(34, drive).is_empty());
        assert_eq!(
            image.receive(RPDO1, &[0x7E, 0x04, 0, 0x20]),
            Err(PdoError::TooShort)
        );
        assert_eq!(
            image.receive(RPDO1, &[0x7E, 0x04, 0, 0x20, 0, 0, 0, 0, 1]),
            Ok(Read::Longer)
        );
        let tpdos = image.sync(34, drive);
        assert_eq!(taken.take(), [(0x047E, vec![0x2000, 0, 0, 9, 8])]);
        let ids: Vec<u16> = tpdos.iter().map(CanFrame::id).collect();
        assert_eq!(ids, [0x1A2, 0x2A2]);
        assert_eq!(tpdos[0].data(), [0x37, 0x0B, 1, 0, 2, 0, 3, 0]);
        image.stop();
        assert!(image.sync(34, drive).is_empty());
    }

    #[test]
    fn three_values_have_no_pdo_2() {
        let mut words = [0; 6];
        let r = read_words(RPDO2, InverterSeries::Sk2xxe, &[1, 0, 2, 0], &mut words);
        assert_eq!(r, Err(PdoError::NotMapped));
        let tpdo1 = Function::Tpdo { number: 1 };
        let r = read_words(
            tpdo1,
            InverterSeries::Sk2xxe,
            &[1, 0, 2, 0, 3, 0, 4, 0],
            &mut words,
        );
        assert_eq!((r, words), (Ok(Read::Exact), [1, 2, 3, 4, 0, 0]));
    }
}
