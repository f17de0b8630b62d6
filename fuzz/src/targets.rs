//! Every fuzz target by name: the name of its libFuzzer binary (`fuzz_targets/<name>.rs`) and
//! of its corpus folder (`corpus/<name>/`).

use crate::{devices, parsers};

/// A fuzz target: its name and the function it runs on the fuzzer's bytes.
#[derive(Debug, Clone, Copy)]
pub struct Target {
    /// The binary's and the corpus folder's name.
    pub name: &'static str,
    /// Runs one input; panics on a crash.
    pub run: fn(&[u8]),
}

/// The targets of the codecs and the devices.
pub const CODECS_AND_DEVICES: &[Target] = &[
    Target {
        name: "ecat",
        run: parsers::ecat,
    },
    Target {
        name: "epl",
        run: parsers::epl,
    },
    Target {
        name: "pnio",
        run: parsers::pnio,
    },
    Target {
        name: "pnio_rpc",
        run: parsers::pnio_rpc,
    },
    Target {
        name: "enip",
        run: parsers::enip,
    },
    Target {
        name: "nord",
        run: parsers::nord,
    },
    Target {
        name: "can",
        run: parsers::can,
    },
    Target {
        name: "canopen",
        run: parsers::canopen,
    },
    Target {
        name: "lldp",
        run: parsers::lldp,
    },
    Target {
        name: "device_ecat",
        run: devices::device_ecat,
    },
    Target {
        name: "device_epl",
        run: devices::device_epl,
    },
    Target {
        name: "device_pnio",
        run: devices::device_pnio,
    },
    Target {
        name: "device_enip",
        run: devices::device_enip,
    },
    Target {
        name: "device_can",
        run: devices::device_can,
    },
];

/// The targets of the harness's readers (feature `texts`).
#[cfg(feature = "texts")]
pub const TEXTS: &[Target] = &[
    Target {
        name: "suite",
        run: crate::texts::suite,
    },
    Target {
        name: "description",
        run: crate::texts::description,
    },
];
/// The targets of the harness's readers: none without feature `texts`.
#[cfg(not(feature = "texts"))]
pub const TEXTS: &[Target] = &[];

/// Every target built: the codecs, the devices and the readers.
pub fn all() -> impl Iterator<Item = &'static Target> {
    CODECS_AND_DEVICES.iter().chain(TEXTS)
}

/// The target of that name.
pub fn by_name(name: &str) -> Option<&'static Target> {
    all().find(|t| t.name == name)
}
