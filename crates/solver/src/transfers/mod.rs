//! Transfers beyond the G2P stage's own PIC, FLIP and APIC: XPIC(m), and
//! the serial particle-grid sums that it, the null-space filter and the
//! multiphase drag share.

pub mod serial;
pub mod xpic;
