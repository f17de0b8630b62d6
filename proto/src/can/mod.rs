//! CAN 2.0A as the NORD system bus carries it (CANopen on CAN, CiA 301): the classical base
//! frame, the Linux SocketCAN `struct can_frame` a raw CAN socket reads and writes, and the
//! ASCII protocol of the Linux-CAN project's socketcand, which carries frames over TCP.
//!
//! - [`frame`]: [`CanFrame`], an 11-bit identifier, the RTR flag and 0..8 data bytes;
//! - [`socketcan`]: the 16-byte `struct can_frame` of `linux/can.h`, with its error frames;
//! - [`socketcand`]: socketcand's `< … >` messages, framed out of a byte stream.
//!
//! The system bus is CAN 2.0A: an extended (29-bit) frame is an
//! [`crate::wire::Error::CanExtended`], never silently truncated to 11 bits. Every parser
//! returns `Err` naming the field on malformed input and never panics on any byte sequence.

pub mod frame;
pub mod no_panic;
pub mod socketcan;
pub mod socketcand;

pub use frame::CanFrame;
