//! The DUT's identity for the run's record, and the connection check that reads it.
//!
//! Before its first case a run opens the DUT once per profile and asks who it is: over the
//! bus's identity service where the bus has one ([`Binding::identity`]), else through the
//! NORD information parameters on the parameter channel. The same request is the connection
//! check: a DUT that cannot be reached, or is reached and never answers, ends the run with one
//! error instead of an error per case (see `runner::run`).

use proto::nord::params::{self, Owner};
use proto::nord::{ArrayElement, ParamNumber, Product};

use crate::binding::{Binding, StepError};
use crate::outcome::Identity;
use crate::profile::Profile;
use crate::suite::{Action, OrderSpec, Target};

/// P171 "Software version" of the bus modules: [-01] version, [-02] revision, one decimal
/// (BU 0590 §5.1.3 p. 35, BU 2200 §7.1.3 p. 53).
const SOFTWARE_VERSION: u16 = 171;

/// Who the DUT says it is.
pub(crate) fn identify(dut: &mut dyn Binding, profile: &Profile) -> Result<Identity, StepError> {
    if let Some(id) = dut.identity() {
        return id;
    }
    match profile.product {
        Some(product) => by_parameters(dut, product),
        None => Ok(Identity {
            source: "none: the binding has no identity service".into(),
            ..Identity::default()
        }),
    }
}

/// The information parameters the product catalogues, read over the parameter channel.
fn by_parameters(dut: &mut dyn Binding, product: Product) -> Result<Identity, StepError> {
    let number =
        ParamNumber::new(i64::from(SOFTWARE_VERSION)).map_err(|e| StepError::Suite(e.into()))?;
    if params::lookup(product, Owner::Interface, number).is_none() {
        return Ok(Identity {
            source: format!(
                "none: the data-record link has no identity service and the {} catalogues no software version (P171)",
                product.name()
            ),
            ..Identity::default()
        });
    }
    let mut element = |n: u8| -> Result<i64, StepError> {
        let order = OrderSpec {
            element: Some(ArrayElement::new(i64::from(n)).map_err(|e| StepError::Suite(e.into()))?),
            ..OrderSpec::read(Target::Interface, number)
        };
        let seen = dut.perform(&Action::Read(order))?;
        if let Some(r) = seen.refusal {
            return Err(StepError::Refused(format!("P171 [-{n:02}]: {r}").into()));
        }
        seen.fields["value"].as_i64().ok_or_else(|| {
            StepError::Protocol(format!("P171 [-{n:02}] has no value: {}", seen.fields).into())
        })
    };
    let (version, revision) = (element(1)?, element(2)?);
    Ok(Identity {
        source: "P171 software version over the parameter channel".into(),
        revision: Some(format!("{}.{} R{revision}", version / 10, version % 10)),
        ..Identity::default()
    })
}
