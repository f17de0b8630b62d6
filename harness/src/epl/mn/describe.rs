//! POWERLINK frames in words, for transcripts.

use proto::epl::asnd::{IdentResponse, NmtCommandFrame, StatusResponse};
use proto::epl::frame::Body;
use proto::epl::sdo::{SdoFrame, Segmentation};
use proto::epl::{EplRepr, ServiceId};

/// One line for a frame.
pub(crate) fn describe(r: &EplRepr) -> String {
    match &r.body {
        Body::Soc(_) => "SoC".into(),
        Body::Preq(p) => format!(
            "PReq to node {}{} size {}",
            r.dst,
            if p.rd { " RD" } else { "" },
            p.payload.len()
        ),
        Body::Pres(p) => format!(
            "PRes from node {} {}{}{} size {}",
            r.src,
            p.state,
            if p.rd { " RD" } else { "" },
            if p.rs > 0 {
                format!(" RS {}", p.rs)
            } else {
                String::new()
            },
            p.payload.len()
        ),
        Body::Soa(s) => format!("SoA {} to node {} (MN {})", s.service, s.target, s.state),
        Body::Asnd(a) => {
            let what = match a.service {
                ServiceId::IDENT_RESPONSE => IdentResponse::parse(&a.payload).map_or_else(
                    |e| format!("malformed: {e}"),
                    |i| {
                        format!(
                            "{} vendor {:08X}h product {:08X}h revision {:08X}h IP {} \"{}\"",
                            i.state, i.vendor_id, i.product_code, i.revision, i.ip, i.hostname
                        )
                    },
                ),
                ServiceId::STATUS_RESPONSE => StatusResponse::parse(&a.payload).map_or_else(
                    |e| format!("malformed: {e}"),
                    |s| {
                        let codes: Vec<String> = s
                            .entries
                            .iter()
                            .map(|e| format!("{:04X}h", e.code))
                            .collect();
                        format!(
                            "{} error register {:02X}h, errors [{}]",
                            s.state,
                            s.error_register,
                            codes.join(", ")
                        )
                    },
                ),
                ServiceId::NMT_COMMAND => NmtCommandFrame::parse(&a.payload)
                    .map_or_else(|e| format!("malformed: {e}"), |c| c.command.to_string()),
                ServiceId::SDO => sdo(&a.payload),
                _ => String::new(),
            };
            format!("ASnd {} {}→{} {what}", a.service, r.src, r.dst)
        }
    }
}

/// An SDO frame in words.
pub(crate) fn sdo(bytes: &[u8]) -> String {
    let f = match SdoFrame::parse(bytes) {
        Ok(f) => f,
        Err(e) => return format!("malformed SDO: {e}"),
    };
    let seq = format!(
        "seq {}/{:?} ack {}/{:?}",
        f.seq.ssnr, f.seq.scon, f.seq.rsnr, f.seq.rcon
    );
    let Some(c) = f.command else {
        return seq;
    };
    let mut s = format!(
        "{seq} {}{:?} tid {}",
        if c.response { "response " } else { "" },
        c.command,
        c.transaction
    );
    if let Some(code) = c.abort_code() {
        s.push_str(&format!(" ABORT {code:08X}h"));
        return s;
    }
    if c.segmentation != Segmentation::Expedited {
        s.push_str(&format!(" {:?}", c.segmentation));
    }
    if !c.response && c.segmentation == Segmentation::Expedited {
        if let Ok((index, sub, data)) = c.by_index() {
            s.push_str(&format!(" {index:04X}h/{sub:02X}h"));
            if !data.is_empty() {
                s.push_str(&format!(" data {}", crate::hex::hex(data)));
            }
        }
    } else if !c.payload.is_empty() {
        s.push_str(&format!(" data {}", crate::hex::hex(&c.payload)));
    }
    s
}

/// A UDP datagram to or from port 3819.
pub(crate) fn udp(datagram: &[u8]) -> String {
    match SdoFrame::strip_udp(datagram) {
        Ok(b) => format!("UDP 3819 SDO {}", sdo(b)),
        Err(e) => format!("UDP 3819 malformed: {e}"),
    }
}
