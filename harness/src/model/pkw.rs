//! Compute functions of the `pkw` and `ppo` themes: the parameter channel and PPO telegrams.

use proto::nord::pkw::{supported_orders, ErrorNumber, Ind, OrderLabel, PkwRepr, ResponseLabel};
use proto::nord::ppo::PpoType;
use serde_json::{json, Value};

use super::{Args, ComputeError, ComputeFn, Ctx};
use crate::hex::hex;

fn fields(r: &PkwRepr) -> Value {
    json!({
        "bytes": hex(&r.emit_bytes()),
        "ak": r.ak, "spm": r.spm, "pnu": r.pnu, "ind": r.ind, "pwe": r.pwe,
        "value": r.value(),
        "set": Ind(r.ind).set(), "element": Ind(r.ind).element(), "subindex": Ind(r.ind).subindex(),
        "order": OrderLabel(r.ak).meaning(), "response": ResponseLabel(r.ak).meaning(),
    })
}

fn decode(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let text = a.str("bytes")?;
    let bytes: Vec<u8> = text
        .split_whitespace()
        .map(|t| u8::from_str_radix(t, 16))
        .collect::<Result<_, _>>()
        .map_err(|_| ComputeError::BadArg {
            arg: "bytes".into(),
            why: format!("`{text}` is not hex bytes"),
        })?;
    if bytes.len() > proto::nord::pkw::PKW_LEN {
        return Err(ComputeError::Refused(format!(
            "a PKW telegram is 8 bytes, got {}",
            bytes.len()
        )));
    }
    let r = PkwRepr::parse(&bytes).map_err(|e| ComputeError::Refused(e.to_string()))?;
    Ok(fields(&r))
}

fn encode(c: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let ind = match a.opt_int("ind")? {
        Some(i) => i as u16,
        None => {
            let addr = super::addr::address(a)?;
            Ind::for_address(addr.set, addr.element).raw()
        }
    };
    let pnu = match a.opt_int("pnu")? {
        Some(p) => p as u16,
        None => proto::nord::addr::profinet_pnu(
            c.product,
            proto::nord::ParamNumber::new(a.int("param")?)?,
        ),
    };
    let r = PkwRepr {
        ak: a.int("ak")? as u8,
        spm: false,
        pnu,
        ind,
        pwe: a.opt_int("value")?.unwrap_or(0) as u32,
    };
    Ok(fields(&r))
}

/// The functions of this theme.
pub(super) const FNS: &[ComputeFn] = &[
    ComputeFn {
        name: "pkw.decode",
        doc: "Fields of an 8-byte PKW telegram (BU 0620 §2.5.6.3)",
        run: decode,
    },
    ComputeFn {
        name: "pkw.encode",
        doc: "PKW telegram from ak, param/pnu, set/element/ind, value",
        run: encode,
    },
    ComputeFn {
        name: "pkw.ind",
        doc: "IND word of a parameter set / array element (BU 0620 §2.5.6.3)",
        run: |_: &Ctx, a: &Args| {
            let addr = super::addr::address(a)?;
            Ok(json!({ "ind": Ind::for_address(addr.set, addr.element).raw() }))
        },
    },
    ComputeFn {
        name: "pkw.response_for",
        doc: "Positive response labels of an order label (BU 0620 §2.5.6.3 table)",
        run: |_: &Ctx, a: &Args| {
            let o = OrderLabel(a.int("ak")? as u8);
            let labels: Vec<u8> = o.positive_responses().iter().map(|r| r.0).collect();
            Ok(json!({ "responses": labels, "meaning": o.meaning(), "ram_only": o.is_ram_only() }))
        },
    },
    ComputeFn {
        name: "pkw.error",
        doc: "Meaning of a parameter-channel error number (PWE2 of AK 7)",
        run: |_: &Ctx, a: &Args| {
            Ok(json!({ "meaning": ErrorNumber(a.int("number")? as u16).meaning() }))
        },
    },
    ComputeFn {
        name: "pkw.supported",
        doc: "Order labels a unit supports (first = FI 1 / the interface; else a system-bus FI)",
        run: |c: &Ctx, a: &Args| {
            let first = a.opt_bool("first")?.unwrap_or(true);
            let labels: Vec<u8> = supported_orders(c.product, first)
                .iter()
                .map(|o| o.0)
                .collect();
            Ok(json!({ "labels": labels }))
        },
    },
    ComputeFn {
        name: "ppo.layout",
        doc:
            "PPO type layout: PKW, PZD words, bytes, display code (BU 0620 §2.5.4, BU 0590 §4.1.1)",
        run: |c: &Ctx, a: &Args| {
            let t = PpoType::new(a.int("type")? as u8)
                .map_err(|e| ComputeError::Refused(e.to_string()))?;
            Ok(
                json!({ "pkw": t.has_pkw(), "pzd_words": t.pzd_words(), "bytes": t.byte_len(), "display_code": t.display_code(c.product) }),
            )
        },
    },
];
