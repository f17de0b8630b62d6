//! Compute functions of the `params` theme: the parameter catalogue.

use proto::nord::params::{self, Owner};
use proto::nord::ParamNumber;
use serde_json::{json, Value};

use super::{Args, ComputeError, ComputeFn, Ctx};

fn def(c: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let owner = match a.opt_str("owner")? {
        Some("interface") => Owner::Interface,
        None | Some("inverter") => Owner::Inverter,
        Some(o) => {
            return Err(ComputeError::BadArg {
                arg: "owner".into(),
                why: format!("`{o}` is neither interface nor inverter"),
            })
        }
    };
    let n = ParamNumber::new(a.int("param")?)?;
    let d = params::lookup(c.product, owner, n).ok_or_else(|| {
        ComputeError::Refused(format!(
            "{n} is not in the catalogue of {}",
            c.product.name()
        ))
    })?;
    let element = a.opt_int("element")?.unwrap_or(1) as u8;
    let mut v = serde_json::to_value(d).map_err(|e| ComputeError::Refused(e.to_string()))?;
    v["element_default"] = json!(params::element_default(d, element));
    Ok(v)
}

/// The functions of this theme.
pub(super) const FNS: &[ComputeFn] = &[ComputeFn {
    name: "params.def",
    doc: "Catalogue entry of a parameter: range, default, width, array, set dependence, access",
    run: def,
}];
