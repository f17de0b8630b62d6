//! `harness describe eds --bus can`: the CiA 306 electronic data sheet of one inverter of the
//! NORD system bus as a CANopen node, written from the same sources the simulated node
//! (`sim::can`) answers from: its communication objects and the parameter catalogue at
//! 2000h + P (`crate::dictionary`). A CANopen tool (python-canopen, a configurator) set up from
//! it reads and writes the inverter's parameters by name.
//!
//! The manuals give no EDS for the system bus (it is NORD's internal bus); what the file
//! states beyond the manuals is this project's choice, as `sim::can` documents it: device
//! type 0, 1017h off by default, 1016h watching the interface's heartbeat for P120
//! (`proto::nord::can::InterfaceWatch`), NORD's vendor id 538h, 250 kBaud only (P514, BU 0620
//! §2.6).
//! Its dates are fixed, so that the same product gives the same file.

use std::fmt::Write;

use proto::nord::ecat::{DataType, ObjectCode};
use proto::nord::{Inverter, Product};

use super::{inverter_parameters, parameter, DescribeError, ObjectDoc};

/// VISIBLE_STRING (CiA 301 data type 0009h), beyond [`DataType::code`]'s numbers.
const VISIBLE_STRING: u16 = 0x0009;
/// The parameters' objects start here (object 2000h + P).
const PARAMETERS: u16 = 0x2000;

/// The EDS of inverter `fi` of `product` on the system bus.
pub(crate) fn eds(product: Product, fi: Inverter) -> Result<String, DescribeError> {
    DescribeError::check_inverters(product, fi.get())?;
    let mandatory = vec![
        ObjectDoc::var(0x1000, "Device type", DataType::U32.code(), "ro").default("0x00000000"),
        ObjectDoc::var(0x1001, "Error register", DataType::U8.code(), "ro").default("0"),
        ObjectDoc::compound(
            0x1018,
            "Identity object",
            ObjectCode::Record,
            vec![
                ObjectDoc::var(0, "Highest sub-index supported", DataType::U8.code(), "ro")
                    .default("1"),
                ObjectDoc::var(1, "Vendor-ID", DataType::U32.code(), "ro")
                    .default(format!("0x{:08X}", proto::nord::ecat::VENDOR_ID)),
            ],
        ),
    ];
    let optional = vec![
        ObjectDoc::var(0x1008, "Manufacturer device name", VISIBLE_STRING, "const")
            .default(product.name()),
        ObjectDoc::compound(
            0x1016,
            "Consumer heartbeat time",
            ObjectCode::Array,
            vec![
                ObjectDoc::var(0, "Highest sub-index supported", DataType::U8.code(), "ro")
                    .default("1"),
                ObjectDoc::var(1, "Consumer heartbeat time 1", DataType::U32.code(), "rw").default(
                    format!(
                        "0x{:08X}",
                        proto::nord::can::interface_watch(product).consumer_entry()
                    ),
                ),
            ],
        ),
        ObjectDoc::var(
            0x1017,
            "Producer heartbeat time",
            DataType::U16.code(),
            "rw",
        )
        .default("0"),
    ];
    let manufacturer: Vec<ObjectDoc> = inverter_parameters(product, fi)
        .into_iter()
        .map(|d| parameter(PARAMETERS, "", d))
        .collect();
    let mut s = String::new();
    let failed = |e: std::fmt::Error| DescribeError::Write {
        format: "EDS",
        detail: e.to_string(),
    };
    header(&mut s, product, fi).map_err(failed)?;
    for (section, objects) in [
        ("MandatoryObjects", &mandatory),
        ("OptionalObjects", &optional),
        ("ManufacturerObjects", &manufacturer),
    ] {
        list(&mut s, section, objects).map_err(failed)?;
    }
    Ok(s)
}

fn header(s: &mut String, product: Product, fi: Inverter) -> std::fmt::Result {
    let name = format!("{} FI {}", product.name(), fi.get());
    writeln!(s, "[FileInfo]")?;
    writeln!(s, "FileName=NORD_{}_FI{}.eds", product.name(), fi.get())?;
    writeln!(s, "FileVersion=1\nFileRevision=0\nEDSVersion=4.0")?;
    writeln!(s, "Description={name} on the NORD system bus (CANopen)")?;
    writeln!(s, "CreationTime=12:00PM\nCreationDate=01-01-2026")?;
    writeln!(s, "CreatedBy=harness describe eds --bus can")?;
    writeln!(s, "ModificationTime=12:00PM\nModificationDate=01-01-2026")?;
    writeln!(s, "ModifiedBy=harness describe eds --bus can\n")?;
    writeln!(s, "[DeviceInfo]")?;
    writeln!(s, "VendorName={}", proto::nord::ecat::VENDOR_NAME)?;
    writeln!(s, "VendorNumber=0x{:08X}", proto::nord::ecat::VENDOR_ID)?;
    writeln!(
        s,
        "ProductName={name}\nProductNumber=0x00000000\nRevisionNumber=0x00000000"
    )?;
    writeln!(s, "OrderCode=")?;
    for (rate, on) in [
        (10, 0),
        (20, 0),
        (50, 0),
        (125, 0),
        (250, 1),
        (500, 0),
        (800, 0),
        (1000, 0),
    ] {
        writeln!(s, "BaudRate_{rate}={on}")?;
    }
    writeln!(
        s,
        "SimpleBootUpMaster=0\nSimpleBootUpSlave=1\nGranularity=0"
    )?;
    writeln!(s, "DynamicChannelsSupported=0\nGroupMessaging=0")?;
    writeln!(s, "NrOfRXPDO=0\nNrOfTXPDO=0\nLSS_Supported=0\n")?;
    writeln!(s, "[DummyUsage]")?;
    for d in 1..=7 {
        writeln!(s, "Dummy{d:04}=0")?;
    }
    writeln!(s, "\n[Comments]\nLines=0\n")
}

/// A list section and the objects' own sections.
fn list(s: &mut String, section: &str, objects: &[ObjectDoc]) -> std::fmt::Result {
    writeln!(s, "[{section}]\nSupportedObjects={}", objects.len())?;
    for (n, o) in objects.iter().enumerate() {
        writeln!(s, "{}=0x{:04X}", n + 1, o.at)?;
    }
    writeln!(s)?;
    for o in objects {
        object(s, &format!("{:04X}", o.at), o)?;
        for sub in &o.subs {
            object(s, &format!("{:04X}sub{:X}", o.at, sub.at), sub)?;
        }
    }
    Ok(())
}

fn object(s: &mut String, section: &str, o: &ObjectDoc) -> std::fmt::Result {
    writeln!(s, "[{section}]\nParameterName={}", o.name)?;
    writeln!(s, "ObjectType=0x{:X}", o.object_type)?;
    if !o.subs.is_empty() {
        return writeln!(s, "SubNumber={}\n", o.subs.len());
    }
    if let Some(t) = o.data_type {
        writeln!(s, "DataType=0x{t:04X}")?;
    }
    writeln!(s, "AccessType={}", o.access.unwrap_or("ro"))?;
    if let Some(d) = &o.default {
        writeln!(s, "DefaultValue={d}")?;
    }
    if let Some((lo, hi)) = o.limits {
        writeln!(s, "LowLimit={lo}\nHighLimit={hi}")?;
    }
    writeln!(s, "PDOMapping=0\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn p102_is_an_array_of_its_four_sets_at_2066h() {
        let e = eds(Product::Sk550p, fi(3)).unwrap();
        assert!(e.contains("[2066]\nParameterName=P102 "), "{}", &e[..2000]);
        assert!(e.contains(
            "[2066]\nParameterName=P102 Acceleration time\nObjectType=0x8\nSubNumber=5\n"
        ));
        assert!(e.contains("[2066sub1]\nParameterName=Set 1\nObjectType=0x7\nDataType="));
        assert!(e.contains("BaudRate_250=1\n"));
        // P120 watches FI 1's heartbeat (node 32) for 600 ms (sim::can's choice).
        assert!(e.contains("[1016sub1]\nParameterName=Consumer heartbeat time 1\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x00200258\n"));
        assert!(e.contains("[1018sub1]\nParameterName=Vendor-ID\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x00000538\n"));
    }

    #[test]
    fn the_sk550p_interface_parameters_answer_at_fi_1_only() {
        let fi1 = eds(Product::Sk550p, fi(1)).unwrap();
        let fi2 = eds(Product::Sk550p, fi(2)).unwrap();
        // P870 "Present bus protocol" (BU 0620 §4.3) is the built-in interface's.
        assert!(fi1.contains("[2366]"));
        assert!(!fi2.contains("[2366]"));
    }

    #[test]
    fn an_inverter_beyond_the_products_is_refused() {
        let e = eds(Product::Tu3Pnt, fi(8)).unwrap_err();
        assert!(
            matches!(e, DescribeError::Inverters { asked: 8, .. }),
            "{e:?}"
        );
        assert_eq!(e.to_string(), "tu3-pnt has 1 inverter behind it, not 8");
    }
}
