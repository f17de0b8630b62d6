//! A PROFINET GSDML as the harness plans a Connect from it (PI GSDML specification): the
//! device identity, the first device access point with its submodules (the DAP's own, the
//! interface and the ports), and one I/O module in a slot it is allowed in.

use proto::pnio::plan::ExpectedSub;

use super::xml::{number, Element};
use super::{missing, DescriptionError, Identity};

/// What the harness takes from a GSDML.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Gsdml {
    pub(crate) identity: Identity,
    /// The DAP's submodules (slot of the DAP, no I/O data).
    pub(crate) dap: Vec<ExpectedSub>,
    /// The modules a Connect puts in the slots: one with input and output data where the
    /// DAP allows one, else the first it allows.
    pub(crate) modules: Vec<ExpectedSub>,
    /// The DAP declares DeviceAccessSupported="true": an IO supervisor may open a
    /// DeviceAccess AR to read records without I/O.
    pub(crate) device_access: bool,
}

/// Bytes of a GSDML data type (the simple types; an octet string says its length).
fn data_bytes(item: &Element) -> u16 {
    let len = item.attr("Length").and_then(number);
    match item.attr("DataType").unwrap_or("") {
        "Integer8" | "Unsigned8" => 1,
        "Integer16" | "Unsigned16" => 2,
        "Integer32" | "Unsigned32" | "Float32" => 4,
        "Integer64" | "Unsigned64" | "Float64" => 8,
        _ => len.unwrap_or(0) as u16,
    }
}

/// Input and output bytes of a virtual submodule's IOData.
fn io_lengths(sub: &Element) -> (u16, u16) {
    let sum = |dir: &str| -> u16 {
        sub.child("IOData")
            .and_then(|io| io.child(dir))
            .map_or(0, |d| d.children("DataItem").map(data_bytes).sum())
    };
    (sum("Input"), sum("Output"))
}

/// The first slot of `1..4` or `1 3 5`.
fn first_slot(s: &str) -> Option<u16> {
    let first = s.split_whitespace().next()?;
    let lo = first.split("..").next()?;
    lo.parse().ok()
}

fn ident(e: &Element, attr: &str) -> Option<u32> {
    e.attr(attr).and_then(number).map(|v| v as u32)
}

/// Reads a GSDML's root element.
pub(crate) fn parse(root: &Element, file: &str) -> Result<Gsdml, DescriptionError> {
    let di = root
        .find("DeviceIdentity")
        .ok_or_else(|| missing(file, "DeviceIdentity"))?;
    let identity = Identity {
        vendor: ident(di, "VendorID"),
        product: ident(di, "DeviceID"),
        revision: None,
        name: di
            .child("VendorName")
            .and_then(|v| v.attr("Value"))
            .map(str::to_string),
    };
    let dap = root
        .find("DeviceAccessPointItem")
        .ok_or_else(|| missing(file, "DeviceAccessPointItem"))?;
    let dap_slot = dap.attr("FixedInSlots").and_then(first_slot).unwrap_or(0);
    let dap_ident = ident(dap, "ModuleIdentNumber")
        .ok_or_else(|| missing(file, "the DAP's ModuleIdentNumber"))?;
    let sub = |subslot: u16, ident: u32, lens: (u16, u16)| ExpectedSub {
        slot: dap_slot,
        module_ident: dap_ident,
        subslot,
        ident,
        input_len: lens.0,
        output_len: lens.1,
    };
    let mut subs = Vec::new();
    for v in dap.descendants("VirtualSubmoduleItem") {
        let subslot = v.attr("FixedInSubslots").and_then(first_slot).unwrap_or(1);
        subs.push(sub(
            subslot,
            ident(v, "SubmoduleIdentNumber").unwrap_or(0),
            io_lengths(v),
        ));
    }
    for kind in ["InterfaceSubmoduleItem", "PortSubmoduleItem"] {
        for s in dap.descendants(kind) {
            let subslot = s.attr("SubslotNumber").and_then(number).unwrap_or(0) as u16;
            subs.push(sub(
                subslot,
                ident(s, "SubmoduleIdentNumber").unwrap_or(0),
                (0, 0),
            ));
        }
    }
    let items = root.descendants("ModuleItem");
    let mut candidates = Vec::new();
    for r in dap.descendants("ModuleItemRef") {
        let target = r.attr("ModuleItemTarget").unwrap_or("");
        let Some(m) = items.iter().find(|m| m.attr("ID") == Some(target)) else {
            continue;
        };
        let Some(slot) = r
            .attr("FixedInSlots")
            .or(r.attr("AllowedInSlots"))
            .and_then(first_slot)
        else {
            continue;
        };
        let Some(v) = m.find("VirtualSubmoduleItem") else {
            continue;
        };
        let (input_len, output_len) = io_lengths(v);
        candidates.push(ExpectedSub {
            slot,
            module_ident: ident(m, "ModuleIdentNumber").unwrap_or(0),
            subslot: v.attr("FixedInSubslots").and_then(first_slot).unwrap_or(1),
            ident: ident(v, "SubmoduleIdentNumber").unwrap_or(0),
            input_len,
            output_len,
        });
    }
    let both = candidates
        .iter()
        .position(|c| c.input_len > 0 && c.output_len > 0)
        .unwrap_or(0);
    Ok(Gsdml {
        identity,
        dap: subs,
        modules: candidates.get(both).cloned().into_iter().collect(),
        device_access: dap.attr("DeviceAccessSupported") == Some("true"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dap_and_an_io_module_make_the_connect() {
        let text = r#"<ISO15745Profile><ProfileBody><DeviceIdentity VendorID="0x0493" DeviceID="0x0002"><VendorName Value="rt-labs"/></DeviceIdentity>
          <ApplicationProcess><DeviceAccessPointList>
            <DeviceAccessPointItem ID="D" ModuleIdentNumber="0x00000001" FixedInSlots="0" DeviceAccessSupported="false">
              <UseableModules>
                <ModuleItemRef ModuleItemTarget="IN" AllowedInSlots="1..4"/>
                <ModuleItemRef ModuleItemTarget="IO" AllowedInSlots="2..4"/>
              </UseableModules>
              <VirtualSubmoduleList><VirtualSubmoduleItem SubmoduleIdentNumber="0x1" FixedInSubslots="1"/></VirtualSubmoduleList>
              <SystemDefinedSubmoduleList>
                <InterfaceSubmoduleItem SubslotNumber="32768" SubmoduleIdentNumber="0x8000"/>
                <PortSubmoduleItem SubslotNumber="32769" SubmoduleIdentNumber="0x8001"/>
              </SystemDefinedSubmoduleList>
            </DeviceAccessPointItem></DeviceAccessPointList>
          <ModuleList>
            <ModuleItem ID="IN" ModuleIdentNumber="0x30"><VirtualSubmoduleList><VirtualSubmoduleItem SubmoduleIdentNumber="0x130">
              <IOData><Input><DataItem DataType="Unsigned8"/></Input></IOData></VirtualSubmoduleItem></VirtualSubmoduleList></ModuleItem>
            <ModuleItem ID="IO" ModuleIdentNumber="0x40"><VirtualSubmoduleList><VirtualSubmoduleItem SubmoduleIdentNumber="0x140">
              <IOData><Input><DataItem DataType="Float32"/><DataItem DataType="Unsigned32"/></Input>
              <Output><DataItem DataType="OctetString" Length="8"/></Output></IOData></VirtualSubmoduleItem></VirtualSubmoduleList></ModuleItem>
          </ModuleList></ApplicationProcess></ProfileBody></ISO15745Profile>"#;
        let root = crate::description::xml::parse(text, "g").unwrap();
        let g = parse(&root, "g").unwrap();
        assert_eq!(
            (g.identity.vendor, g.identity.product),
            (Some(0x493), Some(2))
        );
        let subslots: Vec<u16> = g.dap.iter().map(|s| s.subslot).collect();
        assert_eq!(subslots, [1, 0x8000, 0x8001]);
        assert!(g.dap.iter().all(|s| s.slot == 0 && s.module_ident == 1));
        assert_eq!(g.modules.len(), 1);
        let m = &g.modules[0];
        assert_eq!((m.slot, m.module_ident, m.ident), (2, 0x40, 0x140));
        assert_eq!((m.input_len, m.output_len), (8, 8));
        assert!(!g.device_access);
    }
}
