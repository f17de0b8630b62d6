//! The cyclic layout a controller puts in its Connect (IEC 61158-6-10 "IOCRBlockReq" frame
//! offsets): from the submodules it expects, where each data object (data, then its IOPS) and
//! each consumer status (IOCS) lies in the input and the output C_SDU.
//!
//! The standard's rule: a submodule with input data, or with none at all (NO_IO), has its
//! data object in the input CR and its IOCS in the output CR; one with output data has its
//! data object in the output CR and its IOCS in the input CR; an INPUT_OUTPUT submodule has
//! both. Data objects come first, in the order given, then the IOCS; a C_SDU is at least 40
//! bytes.

use super::block::{
    DataDescription, DataDirection, ExpectedApi, ExpectedSubmodule, ExpectedSubmoduleBlockReq,
    IocrApi, IocrEntry, SubmoduleProperties,
};
use super::rt::{MAX_C_SDU, MIN_C_SDU};
use crate::wire::Error;

/// One submodule as the controller expects it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExpectedSub {
    /// SlotNumber.
    pub slot: u16,
    /// ModuleIdentNumber of the slot's module.
    pub module_ident: u32,
    /// SubslotNumber.
    pub subslot: u16,
    /// SubmoduleIdentNumber.
    pub ident: u32,
    /// Input data bytes (device → controller).
    pub input_len: u16,
    /// Output data bytes (controller → device).
    pub output_len: u16,
}

impl ExpectedSub {
    fn properties(&self) -> SubmoduleProperties {
        match (self.input_len, self.output_len) {
            (0, 0) => SubmoduleProperties::NO_IO,
            (_, 0) => SubmoduleProperties::INPUT,
            (0, _) => SubmoduleProperties::OUTPUT,
            _ => SubmoduleProperties::INPUT_OUTPUT,
        }
    }

    /// Whether its data object goes in the input CR (input data or none at all).
    fn in_input(&self) -> bool {
        self.input_len > 0 || self.output_len == 0
    }

    fn in_output(&self) -> bool {
        self.output_len > 0
    }
}

/// Where one submodule's data object lies in a C_SDU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Place {
    /// SlotNumber.
    pub slot: u16,
    /// SubslotNumber.
    pub subslot: u16,
    /// Offset of the data; its IOPS follows it.
    pub offset: usize,
    /// Data bytes.
    pub len: usize,
}

/// One CR's layout.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CrLayout {
    /// DataLength.
    pub data_length: u16,
    /// The entries of the IOCRBlockReq (API 0).
    pub api: IocrApi,
    /// The data objects, for reading and writing frames.
    pub data: Vec<Place>,
    /// The IOCS (`len` 0): consumer statuses of the other direction's data objects.
    pub iocs: Vec<Place>,
}

/// The layout of both CRs and the ExpectedSubmoduleBlockReq.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Plan {
    /// The input CR (device → controller).
    pub input: CrLayout,
    /// The output CR (controller → device).
    pub output: CrLayout,
    /// What the controller expects, slot by slot.
    pub expected: ExpectedSubmoduleBlockReq,
}

impl Plan {
    /// Lays out `subs` (in slot order as given). A C_SDU over 1440 bytes is
    /// [`Error::TooLong`].
    pub fn new(subs: &[ExpectedSub]) -> Result<Plan, Error> {
        let mut input = Builder::default();
        let mut output = Builder::default();
        for s in subs {
            if s.in_input() {
                input.data(s, s.input_len);
            }
            if s.in_output() {
                output.data(s, s.output_len);
            }
        }
        for s in subs {
            if s.in_input() {
                output.iocs(s);
            }
            if s.in_output() {
                input.iocs(s);
            }
        }
        Ok(Plan {
            input: input.finish()?,
            output: output.finish()?,
            expected: expected(subs),
        })
    }
}

#[derive(Default)]
struct Builder {
    at: usize,
    layout: CrLayout,
}

impl Builder {
    fn data(&mut self, s: &ExpectedSub, len: u16) {
        let place = self.place(s, usize::from(len));
        self.layout.api.io_data.push(entry(&place));
        self.layout.data.push(place);
        self.at += usize::from(len) + 1;
    }

    fn iocs(&mut self, s: &ExpectedSub) {
        let place = self.place(s, 0);
        self.layout.api.iocs.push(entry(&place));
        self.layout.iocs.push(place);
        self.at += 1;
    }

    fn place(&self, s: &ExpectedSub, len: usize) -> Place {
        Place {
            slot: s.slot,
            subslot: s.subslot,
            offset: self.at,
            len,
        }
    }

    fn finish(mut self) -> Result<CrLayout, Error> {
        if self.at > MAX_C_SDU {
            return Err(Error::TooLong {
                what: "C_SDU",
                len: self.at,
                max: MAX_C_SDU,
            });
        }
        self.layout.data_length = self.at.max(MIN_C_SDU) as u16;
        Ok(self.layout)
    }
}

fn entry(p: &Place) -> IocrEntry {
    IocrEntry {
        slot: p.slot,
        subslot: p.subslot,
        // Offsets stay below MAX_C_SDU, checked in `finish`.
        frame_offset: p.offset.min(usize::from(u16::MAX)) as u16,
    }
}

/// The ExpectedSubmoduleBlockReq of `subs`: one entry per slot, in the order given.
fn expected(subs: &[ExpectedSub]) -> ExpectedSubmoduleBlockReq {
    let mut apis: Vec<ExpectedApi> = Vec::new();
    for s in subs {
        let sub = ExpectedSubmodule {
            subslot: s.subslot,
            ident: s.ident,
            properties: s.properties(),
            data: match s.properties() {
                SubmoduleProperties::NO_IO => vec![DataDescription::new(DataDirection::INPUT, 0)],
                SubmoduleProperties::INPUT => {
                    vec![DataDescription::new(DataDirection::INPUT, s.input_len)]
                }
                SubmoduleProperties::OUTPUT => {
                    vec![DataDescription::new(DataDirection::OUTPUT, s.output_len)]
                }
                _ => vec![
                    DataDescription::new(DataDirection::INPUT, s.input_len),
                    DataDescription::new(DataDirection::OUTPUT, s.output_len),
                ],
            },
        };
        match apis.last_mut() {
            Some(a) if a.slot == s.slot && a.module_ident == s.module_ident => {
                a.submodules.push(sub)
            }
            _ => apis.push(ExpectedApi {
                api: 0,
                slot: s.slot,
                module_ident: s.module_ident,
                module_properties: 0,
                submodules: vec![sub],
            }),
        }
    }
    ExpectedSubmoduleBlockReq { apis }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sub(slot: u16, subslot: u16, input_len: u16, output_len: u16) -> ExpectedSub {
        ExpectedSub {
            slot,
            module_ident: u32::from(slot) + 1,
            subslot,
            ident: u32::from(subslot),
            input_len,
            output_len,
        }
    }

    /// The DAP (no IO) and one PPO 3 module (4 bytes each way): the DAP's IOPS and the
    /// module's data + IOPS in the input C_SDU, then the module's IOCS; the output C_SDU holds
    /// the module's data + IOPS, then the IOCS of both.
    #[test]
    fn the_dap_and_one_module_lay_out_as_the_standard_says() {
        let plan = Plan::new(&[sub(0, 1, 0, 0), sub(3, 1, 4, 4)]).unwrap();
        let offsets = |ps: &[Place]| ps.iter().map(|p| (p.slot, p.offset)).collect::<Vec<_>>();
        assert_eq!(offsets(&plan.input.data), [(0, 0), (3, 1)]);
        assert_eq!(offsets(&plan.input.iocs), [(3, 6)]);
        assert_eq!(offsets(&plan.output.data), [(3, 0)]);
        assert_eq!(offsets(&plan.output.iocs), [(0, 5), (3, 6)]);
        assert_eq!(plan.input.data_length, 40);
        assert_eq!(plan.expected.apis.len(), 2);
        assert_eq!(
            plan.expected.apis[1].submodules[0].properties,
            SubmoduleProperties::INPUT_OUTPUT
        );
    }

    #[test]
    fn a_c_sdu_over_1440_bytes_is_refused() {
        let subs: Vec<_> = (1..=8).map(|s| sub(s, 1, 200, 0)).collect();
        assert!(matches!(Plan::new(&subs), Err(Error::TooLong { .. })));
    }
}
