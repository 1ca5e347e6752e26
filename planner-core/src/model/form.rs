//! Path forms: words over {R, L} (arc, line) with no two lines in a row.
//!
//! The catalogue is ordered as the paper lists the forms: by control degree N, then with R before L
//! (N = 1: R, L; N = 2: RR, RL, LR; N = 3: RRR, RRL, RLR, LRR, LRL; ...).

use serde::{Deserialize, Serialize};

/// Largest control degree (segments per path) the planner has room for.
pub const MAX_CONTROL_DEGREE: usize = 4;

/// Number of forms with at most [`MAX_CONTROL_DEGREE`] segments (2 + 3 + 5 + 8).
pub const FORM_COUNT: usize = 18;

/// The kind of one segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SegmentKind {
    /// A constant-curvature arc (insertion without rotation).
    Arc,
    /// A straight line (insertion while spinning fast).
    Line,
}

impl SegmentKind {
    /// The letter the paper uses for this kind.
    pub fn letter(self) -> char {
        match self {
            SegmentKind::Arc => 'R',
            SegmentKind::Line => 'L',
        }
    }
}

/// One path form. Segment `i` is an arc when bit `i` of `arcs` is set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Form {
    len: u8,
    arcs: u8,
}

impl Form {
    /// Builds a form from its segment count and arc mask; `None` for an empty, too long or LL word.
    pub fn new(len: usize, arcs: u8) -> Option<Form> {
        if len == 0 || len > MAX_CONTROL_DEGREE || u32::from(arcs) >> len != 0 {
            return None;
        }
        let lines = !arcs & ((1u8 << len) - 1);
        if lines & (lines >> 1) != 0 {
            return None;
        }
        Some(Form {
            len: len as u8,
            arcs,
        })
    }

    /// Parses a word such as `"RLR"` (case-insensitive).
    pub fn parse(word: &str) -> Option<Form> {
        let mut arcs = 0u8;
        let mut len = 0usize;
        for c in word.trim().chars() {
            if len >= MAX_CONTROL_DEGREE {
                return None;
            }
            match c {
                'R' | 'r' => arcs |= 1 << len,
                'L' | 'l' => {}
                _ => return None,
            }
            len += 1;
        }
        Form::new(len, arcs)
    }

    /// Control degree N: the number of segments.
    pub fn len(self) -> usize {
        usize::from(self.len)
    }

    /// Always false: a form has at least one segment.
    pub fn is_empty(self) -> bool {
        self.len == 0
    }

    /// Kind of segment `i` (segments past the end read as lines).
    pub fn kind(self, i: usize) -> SegmentKind {
        if i < MAX_CONTROL_DEGREE && self.arcs & (1 << i) != 0 {
            SegmentKind::Arc
        } else {
            SegmentKind::Line
        }
    }

    /// Number of arc segments.
    pub fn arc_count(self) -> usize {
        self.arcs.count_ones() as usize
    }

    /// The word as fixed-size text, e.g. `"RL"`.
    pub fn word(self) -> heapless::String<MAX_CONTROL_DEGREE> {
        let mut s = heapless::String::new();
        for i in 0..self.len() {
            // Cannot overflow: the capacity is the longest form.
            let _ = s.push(self.kind(i).letter());
        }
        s
    }

    /// Position of this form in [`catalogue`].
    pub fn index(self) -> usize {
        catalogue()
            .iter()
            .position(|f| *f == self)
            .unwrap_or(FORM_COUNT)
    }
}

impl core::fmt::Display for Form {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.word().as_str())
    }
}

/// Every form up to [`MAX_CONTROL_DEGREE`], in the paper's order.
pub fn catalogue() -> [Form; FORM_COUNT] {
    let mut out = [Form { len: 1, arcs: 1 }; FORM_COUNT];
    let mut n = 0;
    for len in 1..=MAX_CONTROL_DEGREE {
        // R sorts before L: walk words in lexicographic order with R as the smaller letter.
        for rank in 0..(1u32 << len) {
            let mut arcs = 0u8;
            for i in 0..len {
                let letter_is_l = rank & (1 << (len - 1 - i)) != 0;
                if !letter_is_l {
                    arcs |= 1 << i;
                }
            }
            if let Some(form) = Form::new(len, arcs) {
                if n < FORM_COUNT {
                    out[n] = form;
                    n += 1;
                }
            }
        }
    }
    out
}

/// A set of forms, as a bit mask over [`catalogue`] indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FormSet(pub u32);

impl FormSet {
    /// Every form whose control degree is at most `max_degree`.
    pub fn up_to_degree(max_degree: usize) -> FormSet {
        let mut bits = 0u32;
        for (i, f) in catalogue().iter().enumerate() {
            if f.len() <= max_degree {
                bits |= 1 << i;
            }
        }
        FormSet(bits)
    }

    /// Adds one form.
    pub fn insert(&mut self, form: Form) {
        let i = form.index();
        if i < FORM_COUNT {
            self.0 |= 1 << i;
        }
    }

    /// Whether the set holds `form`.
    pub fn contains(self, form: Form) -> bool {
        let i = form.index();
        i < FORM_COUNT && self.0 & (1 << i) != 0
    }

    /// Whether no form is selected.
    pub fn is_empty(self) -> bool {
        self.0 & ((1u32 << FORM_COUNT) - 1) == 0
    }

    /// The forms of the set in catalogue order.
    pub fn iter(self) -> impl Iterator<Item = Form> {
        catalogue()
            .into_iter()
            .enumerate()
            .filter(move |(i, _)| self.0 & (1 << i) != 0)
            .map(|(_, f)| f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_matches_the_papers_table() {
        let words: heapless::Vec<heapless::String<4>, 18> =
            catalogue().iter().map(|f| f.word()).collect();
        let expect = [
            "R", "L", "RR", "RL", "LR", "RRR", "RRL", "RLR", "LRR", "LRL", "RRRR", "RRRL", "RRLR",
            "RLRR", "RLRL", "LRRR", "LRRL", "LRLR",
        ];
        assert_eq!(words.len(), expect.len());
        for (w, e) in words.iter().zip(expect) {
            assert_eq!(w.as_str(), e);
        }
    }

    #[test]
    fn parse_rejects_ll_and_junk() {
        assert!(Form::parse("LL").is_none());
        assert!(Form::parse("RLLR").is_none());
        assert!(Form::parse("RX").is_none());
        assert!(Form::parse("").is_none());
        assert!(Form::parse("RRRRR").is_none());
        assert_eq!(Form::parse("lrl").map(|f| f.len()), Some(3));
    }

    #[test]
    fn form_sets_by_degree() {
        assert_eq!(FormSet::up_to_degree(3).iter().count(), 10);
        assert_eq!(FormSet::up_to_degree(1).iter().count(), 2);
        assert!(FormSet::default().is_empty());
    }
}
