//! The DUT's own device description (`run --description FILE`): an EDS, ESI, XDD or GSDML,
//! told apart by its content, not its name. The harness plans from it what it cannot know of
//! another maker's device: which connection to open and how big (EtherNet/IP), which modules
//! to connect (PROFINET), the process-data sizes (POWERLINK), who the device says it is.

pub(crate) mod eds;
mod esi;
mod gsdml;
mod xdd;
pub(crate) mod xml;

use std::fmt;
use std::path::Path;

pub(crate) use eds::Eds;
pub(crate) use esi::Esi;
pub(crate) use gsdml::Gsdml;
pub(crate) use xdd::Xdd;

/// Why a description cannot be used.
#[derive(Debug, thiserror::Error)]
pub(crate) enum DescriptionError {
    #[error("cannot read the description {file}: {source}")]
    Io {
        file: String,
        source: std::io::Error,
    },
    #[error("{file} is none of EDS ([File] first), ESI (<EtherCATInfo>), XDD (<ISO15745ProfileContainer>) or GSDML (<ISO15745Profile> with a DeviceIdentity)")]
    Unknown { file: String },
    #[error("{file}: malformed XML {why}")]
    Xml { file: String, why: String },
    #[error("{file}: no {what}")]
    Missing { file: String, what: String },
    #[error("{file}: {what}")]
    Bad { file: String, what: String },
    #[error(
        "{file} is an {format}, which describes a device of {found}://, and `--dut` is {bus}://"
    )]
    WrongBus {
        file: String,
        format: &'static str,
        found: &'static str,
        bus: &'static str,
    },
}

/// Who a description says the device is.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Identity {
    pub(crate) vendor: Option<u32>,
    pub(crate) product: Option<u32>,
    pub(crate) revision: Option<String>,
    pub(crate) name: Option<String>,
}

impl fmt::Display for Identity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let hex = |v: Option<u32>| v.map_or("?".to_string(), |v| format!("{v:X}h"));
        write!(
            f,
            "{} (vendor {}, product {}, revision {})",
            self.name.as_deref().unwrap_or("unnamed"),
            hex(self.vendor),
            hex(self.product),
            self.revision.as_deref().unwrap_or("?")
        )
    }
}

/// A device description, read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Description {
    Eds(Eds),
    Esi(Esi),
    Xdd(Xdd),
    Gsdml(Gsdml),
}

impl Description {
    /// The bus it describes a device of (a registry name).
    pub(crate) fn bus(&self) -> &'static str {
        match self {
            Description::Eds(_) => "enip",
            Description::Esi(_) => "ecat",
            Description::Xdd(_) => "epl",
            Description::Gsdml(_) => "pnio",
        }
    }

    /// Its format's name, as `harness describe` has it.
    pub(crate) fn format(&self) -> &'static str {
        match self {
            Description::Eds(_) => "EDS",
            Description::Esi(_) => "ESI",
            Description::Xdd(_) => "XDD",
            Description::Gsdml(_) => "GSDML",
        }
    }

    /// Who it says the device is.
    pub(crate) fn identity(&self) -> &Identity {
        match self {
            Description::Eds(d) => &d.identity,
            Description::Esi(d) => &d.identity,
            Description::Xdd(d) => &d.identity,
            Description::Gsdml(d) => &d.identity,
        }
    }

    /// Reads `path`, whatever its name.
    pub(crate) fn read(path: &Path) -> Result<Description, DescriptionError> {
        let file = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| DescriptionError::Io {
            file: file.clone(),
            source,
        })?;
        Description::parse(&text_of(bytes), &file)
    }

    /// Tells the format by content and reads it.
    pub(crate) fn parse(text: &str, file: &str) -> Result<Description, DescriptionError> {
        let text = text.trim_start_matches('\u{feff}');
        if eds::is_eds(text) {
            return eds::parse(text, file).map(Description::Eds);
        }
        if !text.trim_start().starts_with('<') {
            return Err(DescriptionError::Unknown {
                file: file.to_string(),
            });
        }
        let root = xml::parse(text, file)?;
        match root.name.as_str() {
            "EtherCATInfo" => esi::parse(&root, file).map(Description::Esi),
            "ISO15745ProfileContainer" => xdd::parse(&root, file).map(Description::Xdd),
            "ISO15745Profile" if root.find("DeviceAccessPointList").is_some() => {
                gsdml::parse(&root, file).map(Description::Gsdml)
            }
            _ => Err(DescriptionError::Unknown {
                file: file.to_string(),
            }),
        }
    }

    /// The description, if it is one of `bus`'s devices.
    pub(crate) fn for_bus(
        self,
        bus: &'static str,
        file: &str,
    ) -> Result<Description, DescriptionError> {
        if self.bus() == bus {
            Ok(self)
        } else {
            Err(DescriptionError::WrongBus {
                file: file.to_string(),
                format: self.format(),
                found: self.bus(),
                bus,
            })
        }
    }
}

/// A description file's bytes as text: UTF-8, or else Latin-1 byte for byte (EDS files often
/// are).
pub(crate) fn text_of(bytes: Vec<u8>) -> String {
    match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => e.into_bytes().iter().map(|&b| char::from(b)).collect(),
    }
}

/// A missing part, as an error.
fn missing(file: &str, what: &str) -> DescriptionError {
    DescriptionError::Missing {
        file: file.to_string(),
        what: what.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every description the harness writes is read back by the same planner, as the
    /// description of another maker's device is.
    #[test]
    fn our_own_descriptions_are_told_apart_and_read() {
        // `--description` is for `--dut` runs over the buses it plans; the system bus's
        // CiA 306 EDS is written for CANopen masters (python-canopen imports it), not read.
        for bus in crate::buses::BUSES.iter().filter(|b| b.name != "can") {
            for d in bus.descriptions {
                for p in (bus.profiles)() {
                    let n = p.product.map_or(1, |x| x.max_inverters());
                    let Ok(text) = (d.write)(&p, n) else { continue };
                    let read = Description::parse(&text, d.format)
                        .unwrap_or_else(|e| panic!("{} of {}: {e}", d.format, p.name()));
                    assert_eq!(read.bus(), bus.name, "{}", p.name());
                    assert!(read.identity().vendor.is_some(), "{}: {read:?}", p.name());
                }
            }
        }
    }

    #[test]
    fn other_content_is_refused_by_name() {
        let e = Description::parse("hello", "x.txt")
            .unwrap_err()
            .to_string();
        assert!(e.contains("x.txt is none of EDS"), "{e}");
        let e = Description::parse("<a/>", "x.xml").unwrap_err().to_string();
        assert!(e.contains("none of"), "{e}");
        let eds = "[File]\n[Device]\nVendCode = 1;\n";
        let d = Description::parse(eds, "x.eds").unwrap();
        let e = d.for_bus("ecat", "x.eds").unwrap_err().to_string();
        assert!(
            e.contains(
                "x.eds is an EDS, which describes a device of enip://, and `--dut` is ecat://"
            ),
            "{e}"
        );
    }
}
