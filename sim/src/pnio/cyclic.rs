//! The cyclic RT class 1 data of the AR (IEC 61158-6-10 "C_SDU"): where each submodule's data
//! and consumer status lie in the frames (the IOCR blocks' frame offsets), the output frames
//! the controller sends into the inverters' PPOs, the input frames the device sends every
//! SendClockFactor × ReductionRatio × 31.25 µs, and the watchdog on the outputs.
//!
//! An inverter's module carries its PPO as the manuals lay it out (BU 0620 §2.5.5.1, BU 0590
//! §4.1.1): PKW (PPO 1/2) then control word and setpoints from the controller, PKW answer then
//! status word and actual values back, every word big-endian. The device runs each output
//! PPO through [`Device::handle`] and puts the answer in the next input frame.

use std::time::Duration;

use proto::nord::pnio::{self as def};
use proto::nord::ppo::PpoType;
use proto::nord::{Inverter, Product};
use proto::pnio::block::{IocrBlockReq, IocrType};
use proto::pnio::rt::{DataStatus, Iox, RtRepr};
use proto::pnio::FrameId;

use crate::device::Device;
use crate::drive::FaultCode;
use crate::link::{LinkRepr, Unit};

use super::{IoDevice, Out};

/// The time base of SendClockFactor and the cycle counter: 31.25 µs.
const CLOCK_UNIT_NS: u64 = 31_250;

/// A submodule as plugged in the AR.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Submodule {
    pub(super) slot: u16,
    pub(super) subslot: u16,
    /// Bytes of input data (device → controller) the controller expects.
    pub(super) input_len: usize,
    /// Bytes of output data (controller → device).
    pub(super) output_len: usize,
    /// Whether it is the submodule the controller expected (else its IOPS is bad).
    pub(super) proper: bool,
    /// The inverter and PPO type of an inverter's module.
    pub(super) fi: Option<(Inverter, PpoType)>,
}

/// Where one submodule's data object or consumer status lies in a C_SDU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Place {
    /// Index into the AR's submodules.
    sub: usize,
    /// Offset of the data (then its IOPS) or of the IOCS.
    offset: usize,
}

/// One IO CR.
#[derive(Debug, Clone)]
pub(super) struct Cr {
    pub(super) frame_id: u16,
    /// The C_SDU length (DataLength).
    data_length: usize,
    /// The send interval: SendClockFactor × ReductionRatio × 31.25 µs.
    period: Duration,
    /// Input CR: when the last frame went out; output CR: when the last valid one came in.
    last: Option<Duration>,
    /// WatchdogFactor × period: output CR only.
    watchdog: Duration,
    /// The data objects (data + IOPS) this CR carries.
    data: Vec<Place>,
    /// The consumer statuses (IOCS) this CR carries for the other direction's data.
    iocs: Vec<Place>,
}

impl Cr {
    /// The CR of `req` with `frame_id` over `subs`, `None` when an entry names a submodule
    /// that is not in the AR or runs past DataLength (IOCRBlockReq field 8, DataLength).
    pub(super) fn new(req: &IocrBlockReq, frame_id: u16, subs: &[Submodule]) -> Option<Cr> {
        let input = req.iocr_type == IocrType::INPUT;
        let data_length = usize::from(req.data_length);
        let find = |slot: u16, subslot: u16| {
            subs.iter()
                .position(|s| s.slot == slot && s.subslot == subslot)
        };
        let mut data = Vec::new();
        let mut iocs = Vec::new();
        for api in &req.apis {
            for e in &api.io_data {
                let sub = find(e.slot, e.subslot)?;
                let len = if input {
                    subs[sub].input_len
                } else {
                    subs[sub].output_len
                };
                let offset = usize::from(e.frame_offset);
                // The data, then one byte of IOPS.
                if offset + len + 1 > data_length {
                    return None;
                }
                data.push(Place { sub, offset });
            }
            for e in &api.iocs {
                let sub = find(e.slot, e.subslot)?;
                let offset = usize::from(e.frame_offset);
                if offset >= data_length {
                    return None;
                }
                iocs.push(Place { sub, offset });
            }
        }
        let period = Duration::from_nanos(
            CLOCK_UNIT_NS * u64::from(req.send_clock_factor) * u64::from(req.reduction_ratio),
        );
        Some(Cr {
            frame_id,
            data_length,
            period,
            last: None,
            watchdog: period * u32::from(req.watchdog_factor),
            data,
            iocs,
        })
    }
}

/// What the device keeps of the cyclic exchange between frames.
#[derive(Debug, Clone, Default)]
pub(super) struct Image {
    /// Each submodule's input data (by the AR's submodule index).
    pub(super) inputs: Vec<Vec<u8>>,
    /// Each submodule's output data as last received with a good IOPS.
    pub(super) outputs: Vec<Vec<u8>>,
    /// Whether the controller's last output frame was valid (the device's IOCS for it).
    pub(super) outputs_good: bool,
}

impl Image {
    pub(super) fn new(subs: &[Submodule]) -> Image {
        Image {
            inputs: subs.iter().map(|s| vec![0; s.input_len]).collect(),
            outputs: subs.iter().map(|s| vec![0; s.output_len]).collect(),
            outputs_good: false,
        }
    }
}

impl IoDevice {
    /// An RT frame: the controller's outputs when it is the output CR's, dropped otherwise.
    pub(super) fn rt(&mut self, id: FrameId, payload: &[u8], now: Duration) -> Vec<Out> {
        let Some(ar) = self.ar.as_mut() else {
            self.dropped += 1;
            return Vec::new();
        };
        if id.0 != ar.output.frame_id {
            self.dropped += 1;
            return Vec::new();
        }
        let Ok(rt) = RtRepr::parse(payload, Some(ar.output.data_length)) else {
            self.dropped += 1;
            return Vec::new();
        };
        ar.output.last = Some(now);
        let valid = rt.data_status.data_valid() && rt.data_status.run();
        ar.image.outputs_good = valid;
        if !valid || !ar.running() {
            return Vec::new();
        }
        for place in &ar.output.data {
            let sub = &ar.submodules[place.sub];
            let iops = Iox(rt.data[place.offset + sub.output_len]);
            if !iops.is_good() || !sub.proper || lost(&self.lost_fis, sub) {
                continue;
            }
            let bytes = rt.data[place.offset..place.offset + sub.output_len].to_vec();
            let Some((fi, ppo)) = sub.fi else {
                continue;
            };
            let frame = LinkRepr {
                unit: Unit::Inverter(fi),
                ppo_type: ppo.0,
                payload: bytes.clone(),
            }
            .emit();
            if let Ok(answer) = self.device.handle(&frame, now) {
                if let Ok(answer) = LinkRepr::parse(&answer) {
                    let input = &mut ar.image.inputs[place.sub];
                    input.clear();
                    input.extend_from_slice(&answer.payload);
                    input.resize(sub.input_len, 0);
                }
            }
            ar.image.outputs[place.sub] = bytes;
        }
        self.device.set_fieldbus_timeout(false);
        Vec::new()
    }

    /// The input CR's frame when it is due.
    pub(super) fn send_input(&mut self, now: Duration) -> Vec<Out> {
        let station_ok = !self.alarms_pending();
        let Some(ar) = self.ar.as_mut() else {
            return Vec::new();
        };
        let running = ar.running();
        let cr = &mut ar.input;
        if cr.last.is_some_and(|t| now.saturating_sub(t) < cr.period) {
            return Vec::new();
        }
        // On the send clock's grid, not drifting with the poll.
        let period_ns = cr.period.as_nanos().max(1);
        let slot = now.as_nanos() / period_ns * period_ns;
        cr.last = Some(Duration::from_nanos(slot as u64));
        let mut c_sdu = vec![0u8; cr.data_length];
        for place in &cr.data {
            let sub = &ar.submodules[place.sub];
            let data = &ar.image.inputs[place.sub];
            c_sdu[place.offset..place.offset + data.len()].copy_from_slice(data);
            let iops = if sub.proper && !lost(&self.lost_fis, sub) {
                Iox::GOOD
            } else {
                Iox::BAD_BY_DEVICE
            };
            c_sdu[place.offset + sub.input_len] = iops.0;
        }
        for place in &cr.iocs {
            let sub = &ar.submodules[place.sub];
            let good = sub.proper && ar.image.outputs_good;
            c_sdu[place.offset] = if good {
                Iox::GOOD.0
            } else {
                Iox::BAD_BY_DEVICE.0
            };
        }
        let rt = RtRepr {
            frame_id: FrameId(cr.frame_id),
            data: c_sdu,
            cycle_counter: (slot / u128::from(CLOCK_UNIT_NS)) as u16,
            data_status: DataStatus::GOOD
                .with(DataStatus::STATION_OK, station_ok)
                .with(DataStatus::RUN, running),
            transfer_status: 0,
        };
        let dst = ar.controller_mac;
        vec![self.ethernet(dst, rt.emit())]
    }

    /// The output CR's watchdog: no valid output frame for WatchdogFactor cycles in data
    /// exchange ends the AR; the controller is lost (BU 0620 §5.3, BU 0590 §4.1.7).
    pub(super) fn watchdog(&mut self, now: Duration) {
        let Some(ar) = self.ar.as_mut() else {
            return;
        };
        if !ar.running() {
            return;
        }
        let last = *ar.output.last.get_or_insert(now);
        if now.saturating_sub(last) <= ar.output.watchdog {
            return;
        }
        self.ar = None;
        self.lost = true;
        controller_lost(&mut self.device, self.product);
    }
}

/// The controller is gone: the field-bus time-out shows in P872/P173, and every inverter
/// whose telegram monitoring is on (P513) raises the documented error
/// ([`def::controller_loss_error`]); on the SK TU3-PNT the bus status then shows the module
/// error P170 1020 (`Device`'s bus status).
fn controller_lost(device: &mut Device, product: Product) {
    device.set_fieldbus_timeout(true);
    let Some(code) = def::controller_loss_error(product) else {
        return;
    };
    let fault = FaultCode {
        group: code / 10,
        sub: (code % 10) as u8,
    };
    for n in 1..=device.config().inverters {
        let Ok(fi) = Inverter::new(i64::from(n)) else {
            continue;
        };
        if monitored(device, product, fi) {
            // An inverter already in fault keeps that fault.
            let _ = device.raise(fi, fault);
        }
    }
}

/// Whether the telegram time-out is set for `fi`: SK 550P its P513 [-04] "Ethernet" (BU 0620
/// §4.5), behind the SK TU3-PNT the inverter's P513, one value (BU 0590 §5.2.1: −0.1 no error,
/// 0 off, 0.1…100 s), as [`def::telegram_timeout_parameter`] names them.
fn monitored(device: &mut Device, product: Product, fi: Inverter) -> bool {
    match def::telegram_timeout_parameter(product) {
        Some((_, Some(_))) => device.ethernet_timeout(fi).is_some(),
        Some((number, None)) => {
            let Ok(n) = proto::nord::ParamNumber::new(i64::from(number)) else {
                return false;
            };
            device
                .store(Unit::Inverter(fi))
                .ok()
                .and_then(|s| s.read(n, None, None).ok())
                .is_some_and(|tenths| tenths > 0)
        }
        None => false,
    }
}

/// Whether `sub` is the module of an inverter lost from the system bus.
fn lost(lost_fis: &[bool; 8], sub: &Submodule) -> bool {
    sub.fi
        .is_some_and(|(fi, _)| lost_fis.get(usize::from(fi.get()) - 1) == Some(&true))
}
