//! What the EtherCAT speed bench (`harness/benches/ecat/`) needs of the library.
