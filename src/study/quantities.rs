//! The contact quantities a study follows, each read from a level's summary (`summary.json`).

use crate::output::CaseSummary;

/// A quantity: its key in the study's files, its name, where in `summary.json` it is read, and
/// how.
pub struct Quantity {
    pub key: &'static str,
    pub name: &'static str,
    pub source: &'static str,
    pub read: fn(&CaseSummary) -> Option<f64>,
}

/// Contact force, contact radius or half-width, and peak pressure (of the Hertz fit and nodal).
pub const QUANTITIES: [Quantity; 4] = [
    Quantity {
        key: "force",
        name: "contact force",
        source: "magnitude of contact.force_primary",
        read: |s| {
            let f = &s.contact.as_ref()?.force_primary;
            Some(f.iter().map(|c| c * c).sum::<f64>().sqrt())
        },
    },
    Quantity {
        key: "a",
        name: "contact radius / half-width a",
        source: "contact.hertz_fit.a (Hertz ellipse fitted to the primary's pressure)",
        read: |s| Some(s.contact.as_ref()?.hertz_fit?.a),
    },
    Quantity {
        key: "p0",
        name: "peak pressure p0 (Hertz fit)",
        source: "contact.hertz_fit.p0",
        read: |s| Some(s.contact.as_ref()?.hertz_fit?.p0),
    },
    Quantity {
        key: "max_pressure",
        name: "largest nodal pressure",
        source: "contact.max_pressure (on the primary surface)",
        read: |s| Some(s.contact.as_ref()?.max_pressure),
    },
];
