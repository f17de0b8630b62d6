//! The suite model's hold on a bus's own steps: it carries them without looking inside.

use std::any::Any;
use std::fmt;

/// A step in a bus's own terms (an encapsulation message, a datagram, an SDO), carried by the
/// suite model as [`super::Action::Bus`]; only the bus's binding looks inside.
pub(crate) trait BusStep: fmt::Debug + Send + Sync {
    /// The bus it belongs to.
    fn bus(&self) -> &'static str;
    /// One line for reports.
    fn describe(&self) -> String;
    /// What it can do to a real device: make a motor turn, write the EEPROM
    /// ([`crate::effect`]), judged from its bytes alone, conservatively.
    fn effect(&self) -> crate::effect::Effect;
    /// Lets the bus's own binding recover its step type.
    fn as_any(&self) -> &dyn Any;
}
