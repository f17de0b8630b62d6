//! Compute functions of the `addr` theme: the address formulas of `proto::nord::addr`.

use proto::nord::addr;
use proto::nord::{ArrayElement, Inverter, ParamAddress, ParamNumber, ParamSet};
use serde_json::{json, Value};

use super::{Args, ComputeError, ComputeFn, Ctx};

/// The parameter address the args name (`param`, `inverter` = 1, `set`, `element`).
pub(super) fn address(a: &Args) -> Result<ParamAddress, ComputeError> {
    Ok(ParamAddress {
        inverter: Inverter::new(a.opt_int("inverter")?.unwrap_or(1))?,
        number: ParamNumber::new(a.int("param")?)?,
        set: a.opt_int("set")?.map(ParamSet::new).transpose()?,
        element: a.opt_int("element")?.map(ArrayElement::new).transpose()?,
    })
}

fn refused(e: addr::AddrError) -> ComputeError {
    ComputeError::Refused(e.to_string())
}

fn to_json<T: serde::Serialize>(v: T) -> Result<Value, ComputeError> {
    serde_json::to_value(v).map_err(|e| ComputeError::Refused(e.to_string()))
}

/// The functions of this theme.
pub(super) const FNS: &[ComputeFn] = &[
    ComputeFn {
        name: "addr.coe",
        doc: "EtherCAT CoE index/subindex of a parameter (BU 0620 §2.2.7)",
        run: |c: &Ctx, a: &Args| to_json(addr::coe(c.product, address(a)?).map_err(refused)?),
    },
    ComputeFn {
        name: "addr.powerlink",
        doc: "POWERLINK SDO index/subindex (BU 0620 §2.4.6; modules: BU 2200)",
        run: |c: &Ctx, a: &Args| to_json(addr::powerlink(c.product, address(a)?).map_err(refused)?),
    },
    ComputeFn {
        name: "addr.cip",
        doc: "EtherNet/IP class/instance/attribute (BU 0620 §2.3.5, BU 2100)",
        run: |c: &Ctx, a: &Args| to_json(addr::cip(c.product, address(a)?).map_err(refused)?),
    },
    ComputeFn {
        name: "addr.profinet",
        doc: "PROFINET data record, PNU (+1000) and IND (BU 0620 §2.5.6.2, BU 0590 §4.2.2)",
        run: |c: &Ctx, a: &Args| to_json(addr::profinet(c.product, address(a)?).map_err(refused)?),
    },
    ComputeFn {
        name: "addr.can",
        doc: "System-bus CAN IDs of an inverter and its absolute encoder (BU 0620 §3.1)",
        run: |_: &Ctx, a: &Args| {
            to_json(addr::can(Inverter::new(
                a.opt_int("inverter")?.unwrap_or(1),
            )?))
        },
    },
    ComputeFn {
        name: "addr.all",
        doc: "Every protocol address of a parameter for the product (harness addr)",
        run: |c: &Ctx, a: &Args| to_json(addr::all(c.product, address(a)?).map_err(refused)?),
    },
    ComputeFn {
        name: "addr.max_inverters",
        doc: "How many inverters the product addresses",
        run: |c: &Ctx, _: &Args| Ok(json!({ "max": c.product.max_inverters() })),
    },
];
