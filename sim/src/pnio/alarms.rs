//! Diagnosis alarms over the alarm CR (IEC 61158-6-10 RTA, low priority, frame id FE01h):
//! an inverter error raises an incoming channel diagnosis whose ChannelErrorType is the alarm
//! number P700 + 100h (BU 0620 §5.4.2 "incoming event"); its end raises the outgoing one
//! ("Diagnosis disappears"). One alarm at a time (window size 1): the next goes out once the
//! controller's AlarmAck for the last came in; a DATA PDU not acknowledged within
//! RTATimeoutFactor × 100 ms is repeated RTARetries times, then the AR ends.

use std::collections::VecDeque;
use std::time::Duration;

use proto::nord::pnio::{self as def, AlarmSource, ModuleKind};
use proto::nord::Inverter;
use proto::pnio::alarm::{
    AlarmItem, AlarmNotification, AlarmRepr, AlarmSpecifier, AlarmType, ChannelDiagnosis,
    ChannelProperties, RtaBody, RtaPduType, CHANNEL_WHOLE_SUBMODULE,
};
use proto::pnio::block::AlarmCrBlockReq;

use super::{IoDevice, Out};

/// The sequence numbers run 0…7FFFh (IEC 61158-6-10 SendSeqNum).
const SEQ_MASK: u16 = 0x7FFF;
/// AckSeqNum before anything was received: 0xFFFE.
const NOTHING_RECEIVED: u16 = 0xFFFE;

/// A DATA PDU waiting for its acknowledgement.
#[derive(Debug, Clone)]
struct Outstanding {
    notification: AlarmNotification,
    seq: u16,
    sent: Duration,
    tries: u16,
    /// The transport ACK came; the AlarmAck is still awaited.
    acked: bool,
}

/// The device's end of the alarm CR.
#[derive(Debug, Clone)]
pub(super) struct AlarmCr {
    controller_ref: u16,
    device_ref: u16,
    timeout: Duration,
    retries: u16,
    next_seq: u16,
    /// The last SendSeqNum received from the controller.
    received: u16,
    /// AlarmSpecifier.SequenceNumber of the next notification (0…7FFh).
    specifier_seq: u16,
    queue: VecDeque<AlarmNotification>,
    outstanding: Option<Outstanding>,
    /// The RTA retries ran out.
    pub(super) failed: bool,
}

impl AlarmCr {
    /// The alarm CR the controller asked for, with the device's alarm reference.
    pub(super) fn new(req: &AlarmCrBlockReq, device_ref: u16) -> AlarmCr {
        AlarmCr {
            controller_ref: req.local_alarm_reference,
            device_ref,
            timeout: Duration::from_millis(100 * u64::from(req.rta_timeout_factor.max(1))),
            retries: req.rta_retries,
            next_seq: 0,
            received: NOTHING_RECEIVED,
            specifier_seq: 0,
            queue: VecDeque::new(),
            outstanding: None,
            failed: false,
        }
    }

    /// Whether an alarm is queued or awaiting its acknowledgement.
    pub(super) fn busy(&self) -> bool {
        self.outstanding.is_some() || !self.queue.is_empty()
    }

    fn pdu(&self, seq: u16, body: RtaBody) -> AlarmRepr {
        AlarmRepr::data(
            self.controller_ref,
            self.device_ref,
            seq,
            self.received,
            body,
        )
    }

    /// What is due at `now`: the next alarm, or the outstanding one again.
    pub(super) fn due(&mut self, now: Duration) -> Vec<AlarmRepr> {
        if let Some(o) = &self.outstanding {
            if o.acked || now.saturating_sub(o.sent) < self.timeout {
                return Vec::new();
            }
            if o.tries > self.retries {
                self.failed = true;
                return Vec::new();
            }
            let (seq, body) = (o.seq, RtaBody::Notification(o.notification.clone()));
            let out = self.pdu(seq, body);
            if let Some(o) = self.outstanding.as_mut() {
                o.sent = now;
                o.tries += 1;
            }
            return vec![out];
        }
        let Some(mut notification) = self.queue.pop_front() else {
            return Vec::new();
        };
        notification.specifier = AlarmSpecifier::new(self.specifier_seq, notification.specifier.0);
        self.specifier_seq = (self.specifier_seq + 1) & 0x07FF;
        let seq = self.next_seq;
        self.next_seq = (self.next_seq + 1) & SEQ_MASK;
        let out = self.pdu(seq, RtaBody::Notification(notification.clone()));
        self.outstanding = Some(Outstanding {
            notification,
            seq,
            sent: now,
            tries: 1,
            acked: false,
        });
        vec![out]
    }

    /// One RTA PDU from the controller; returns the ACK to send, if any.
    fn receive(&mut self, pdu: &AlarmRepr) -> Vec<AlarmRepr> {
        if let Some(o) = self.outstanding.as_mut() {
            if pdu.ack_seq == o.seq {
                o.acked = true;
            }
        }
        if pdu.pdu_type != RtaPduType::DATA {
            return Vec::new();
        }
        let repeated = pdu.send_seq == self.received;
        self.received = pdu.send_seq;
        if !repeated {
            if let RtaBody::Ack(ack) = &pdu.body {
                let matches = self.outstanding.as_ref().is_some_and(|o| {
                    o.acked
                        && ack.slot == o.notification.slot
                        && ack.subslot == o.notification.subslot
                        && ack.alarm_type == o.notification.alarm_type
                        && ack.specifier.sequence() == o.notification.specifier.sequence()
                });
                if matches {
                    self.outstanding = None;
                }
            }
        }
        let last_sent = self.next_seq.wrapping_sub(1) & SEQ_MASK;
        vec![AlarmRepr::ack(
            pdu.frame_id,
            self.controller_ref,
            self.device_ref,
            last_sent,
            pdu.send_seq,
        )]
    }
}

impl IoDevice {
    /// An alarm frame from the controller.
    pub(super) fn alarm_frame(&mut self, payload: &[u8], _now: Duration) -> Vec<Out> {
        let Ok(pdu) = AlarmRepr::parse(payload) else {
            self.dropped += 1;
            return Vec::new();
        };
        let Some(ar) = self.ar.as_mut() else {
            self.dropped += 1;
            return Vec::new();
        };
        if pdu.dst_endpoint != ar.alarm.device_ref || pdu.src_endpoint != ar.alarm.controller_ref {
            self.dropped += 1;
            return Vec::new();
        }
        if pdu.pdu_type == RtaPduType::ERR {
            // The controller closes the alarm CR: the AR ends.
            self.ar = None;
            return Vec::new();
        }
        let answers = ar.alarm.receive(&pdu);
        let dst = ar.controller_mac;
        self.to_controller(dst, answers)
    }

    /// Alarms that are due, addressed to the controller.
    pub(super) fn alarms_due(&mut self, now: Duration) -> Vec<Out> {
        let Some(ar) = self.ar.as_mut() else {
            return Vec::new();
        };
        let out = ar.alarm.due(now);
        let failed = ar.alarm.failed;
        let dst = ar.controller_mac;
        if failed {
            // RTA retries exhausted: the alarm CR and with it the AR are gone.
            self.ar = None;
            return Vec::new();
        }
        self.to_controller(dst, out)
    }

    fn to_controller(&self, dst: proto::eth::MacAddr, pdus: Vec<AlarmRepr>) -> Vec<Out> {
        pdus.iter()
            .filter_map(|p| p.emit().ok())
            .map(|bytes| self.ethernet(dst, bytes))
            .collect()
    }

    /// Whether an alarm is unacknowledged (the station problem indicator of the input
    /// frames) or an inverter error is present.
    pub(super) fn alarms_pending(&self) -> bool {
        self.raised.iter().any(|a| *a != 0) || self.ar.as_ref().is_some_and(|a| a.alarm.busy())
    }

    /// Inverter errors that came or went since the last look become alarms (in an AR in data
    /// exchange; outside one the device only notes them).
    pub(super) fn fault_alarms(&mut self) {
        let changes = self.device.fault_changes(&mut self.faults);
        for (fi, value) in changes {
            let i = usize::from(fi.get() - 1);
            let before = self.raised[i];
            let now = if value > 0 {
                def::fi_error_alarm(value as u16)
            } else {
                0
            };
            if before == now {
                continue;
            }
            self.raised[i] = now;
            if before != 0 {
                self.diagnosis(fi, false, before);
            }
            if now != 0 {
                self.diagnosis(fi, true, now);
            }
        }
    }

    /// The SK TU3-PNT's test alarm (BU 0590 §5.1.2 P163, p. 35): a value written to [-04]
    /// (slot 3, the FI) is sent as the diagnosis alarm 100h + value from slot 3, "incoming";
    /// back to 0 it is "outgoing".
    pub(super) fn test_alarms(&mut self) {
        if self.product != proto::nord::Product::Tu3Pnt {
            return;
        }
        let (Ok(fi), Ok(p163)) = (Inverter::new(1), proto::nord::ParamNumber::new(163)) else {
            return;
        };
        let slot3 = proto::nord::ArrayElement::new(4).ok();
        let value = self
            .device
            .store(crate::link::Unit::Interface)
            .ok()
            .and_then(|s| s.read(p163, None, slot3).ok())
            .unwrap_or(0);
        let now = match u16::try_from(value) {
            Ok(v) if v > 0 => def::fi_error_alarm(v),
            _ => 0,
        };
        if now == self.test_alarm {
            return;
        }
        if self.test_alarm != 0 {
            self.diagnosis(fi, false, self.test_alarm);
        }
        if now != 0 {
            self.diagnosis(fi, true, now);
        }
        self.test_alarm = now;
    }

    /// FI `fi` is lost from the system bus: alarm 1256 from its slot (BU 0620 §5.4.2), its
    /// data no longer exchanged (IOPS bad).
    pub fn lose_inverter(&mut self, fi: Inverter) -> Result<(), String> {
        let i = usize::from(fi.get()) - 1;
        if fi.get() > self.device.config().inverters {
            return Err(format!("there is no FI {} to lose", fi.get()));
        }
        if !self.lost_fis[i] {
            self.lost_fis[i] = true;
            self.device.lose(fi);
            self.diagnosis(fi, true, def::lost_inverter_alarm());
        }
        Ok(())
    }

    /// Where FI `fi`'s alarms come from, when an AR is in data exchange with its module in
    /// it: the slot, subslot and the module's ident number.
    fn alarm_source(&self, fi: Inverter) -> Option<(u16, u16, u32)> {
        let ar = self.ar.as_ref().filter(|a| a.running())?;
        let (slot, subslot) = def::alarm_location(self.product, AlarmSource::Inverter(fi)).ok()?;
        let sub = ar
            .submodules
            .iter()
            .find(|s| s.slot == slot && s.subslot == subslot && s.proper)?;
        let ident = sub
            .fi
            .and_then(|(_, t)| def::module(self.product, ModuleKind::Ppo(t)))
            .map_or(0, |m| m.ident);
        Some((slot, subslot, ident))
    }

    /// A process alarm from FI 1's module though nothing happened (`harness serve pnio
    /// --misbehave alarm=`): queued on the alarm CR as any alarm, sent when the one before it
    /// is acknowledged; where it comes from, or `None` without an AR in data exchange. NORD's
    /// devices raise diagnosis alarms only (BU 0620 §5.4.2, BU 0590 §6.1): a process alarm
    /// is one their controller cannot expect. Its payload is a manufacturer specific item (USI
    /// 0001h) of two zero bytes, as an application that raises one fills it.
    pub fn spurious_alarm(&mut self) -> Option<(u16, u16)> {
        let fi = Inverter::new(1).ok()?;
        let (slot, subslot, ident) = self.alarm_source(fi)?;
        let ar = self.ar.as_mut()?;
        ar.alarm.queue.push_back(AlarmNotification {
            high: false,
            alarm_type: AlarmType::PROCESS,
            api: 0,
            slot,
            subslot,
            module_ident: ident,
            submodule_ident: ident,
            specifier: AlarmSpecifier(0),
            items: vec![AlarmItem::Other {
                usi: 0x0001,
                data: vec![0, 0],
            }],
        });
        Some((slot, subslot))
    }

    /// Queues an incoming (`appears`) or outgoing channel diagnosis with ChannelErrorType
    /// `number` from FI `fi`'s module, when an AR is in data exchange with that module in it.
    fn diagnosis(&mut self, fi: Inverter, appears: bool, number: u16) {
        let Some((slot, subslot, ident)) = self.alarm_source(fi) else {
            return;
        };
        let Some(ar) = self.ar.as_mut() else {
            return;
        };
        let (alarm_type, properties, flags) = if appears {
            (
                AlarmType::DIAGNOSIS,
                ChannelProperties::APPEARS,
                AlarmSpecifier::CHANNEL_DIAGNOSIS
                    | AlarmSpecifier::SUBMODULE_DIAGNOSIS
                    | AlarmSpecifier::AR_DIAGNOSIS,
            )
        } else {
            (
                AlarmType::DIAGNOSIS_DISAPPEARS,
                ChannelProperties::DISAPPEARS,
                0,
            )
        };
        ar.alarm.queue.push_back(AlarmNotification {
            high: false,
            alarm_type,
            api: 0,
            slot,
            subslot,
            module_ident: ident,
            submodule_ident: ident,
            specifier: AlarmSpecifier(flags),
            items: vec![AlarmItem::ChannelDiagnosis(ChannelDiagnosis {
                channel: CHANNEL_WHOLE_SUBMODULE,
                properties,
                error_type: number,
            })],
        });
    }
}
