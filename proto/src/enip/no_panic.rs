//! Every parser of `proto::enip` on any bytes: each returns `Ok` or a typed `Err`, none
//! panics (the promise of the module documentation), and what parses emits bytes that parse
//! to the same value. The fuzz target `enip` (`fuzz/`) runs [`parse_all`] on its inputs.

use super::cip::{request_service, MrRequest, MrResponse};
use super::cm::{ForwardClose, ForwardOpen, ForwardOpenReply, UnconnectedSend};
use super::cpf::Cpf;
use super::encap::{frame_len, EncapFrame, EncapRepr, RegisterSession, SendData};
use super::epath::EPath;
use super::identity::Identity;
use super::io::IoFrame;

/// Runs every parser of the encapsulation, CPF, CIP, EPath, connection manager, identity and
/// class-1 layers on `b`, and each layer's parser on what the one above it carried.
pub fn parse_all(b: &[u8]) {
    if let Some(n) = frame_len(b) {
        assert!(n >= 24, "a frame is at least its header: {n}");
    }
    if let Ok(f) = EncapFrame::new_checked(b) {
        let _ = (f.command().name(), f.status().name(), f.session(), f.data());
    }
    if let Ok(e) = EncapRepr::parse(b) {
        let again = e.emit().expect("a parsed encapsulation message emits");
        assert_eq!(EncapRepr::parse(&again).as_ref(), Ok(&e));
        let _ = RegisterSession::parse(&e.data);
        if let Ok(s) = SendData::parse(&e.data) {
            let _ = s.emit();
        }
    }
    if let Ok(s) = SendData::parse(b) {
        if let Ok(again) = s.emit() {
            assert_eq!(SendData::parse(&again).as_ref(), Ok(&s));
        }
    }
    let _ = RegisterSession::parse(b);
    if let Ok(c) = Cpf::parse(b) {
        if let Ok(again) = c.emit() {
            assert_eq!(Cpf::parse(&again).as_ref(), Ok(&c));
        }
    }
    let _ = request_service(b);
    if let Ok(r) = MrRequest::parse(b) {
        assert_eq!(MrRequest::parse(&r.emit()).as_ref(), Ok(&r));
        cm(&r.data);
    }
    if let Ok(r) = MrResponse::parse(b) {
        let _ = (r.status().name(), r.emit());
        let _ = ForwardOpenReply::parse(&r.data);
    }
    if let Ok(p) = EPath::parse(b) {
        assert_eq!(EPath::parse(&p.emit()).as_ref(), Ok(&p));
        let _ = (
            p.class_id(),
            p.instance_id(),
            p.attribute_id(),
            p.to_string(),
        );
        let _ = p.connection_points();
    }
    cm(b);
    let _ = Identity::parse_list_identity_item(b);
    for run_idle in [false, true] {
        if let Ok(f) = IoFrame::parse(b, run_idle) {
            let _ = (f.is_run(), f.emit());
        }
    }
    let _ = IoFrame::connection_of(b);
}

/// The connection manager's services on `b`.
fn cm(b: &[u8]) {
    for large in [false, true] {
        if let Ok(f) = ForwardOpen::parse(b, large) {
            let _ = (f.key(), f.timeout_us(), f.emit());
        }
    }
    if let Ok(r) = ForwardOpenReply::parse(b) {
        let _ = r.emit();
    }
    if let Ok(c) = ForwardClose::parse(b) {
        let _ = (c.key(), c.emit());
    }
    if let Ok(u) = UnconnectedSend::parse(b) {
        let _ = u.emit();
        let _ = MrRequest::parse(&u.request);
    }
}
