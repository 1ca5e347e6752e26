//! Fixed-length number lists in scenario files: `[x, y, z]` must have exactly three numbers and
//! a polygon vertex exactly two. serde's own arrays stop reading after N elements, which would
//! plan `center = [0, 30, 50, 1]` as if the fourth number were not there.

use serde::de::{Error, Expected};
use serde::{Deserialize, Deserializer};

struct Exactly(usize);

impl Expected for Exactly {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "exactly {} numbers", self.0)
    }
}

fn exact<E: Error, T, const N: usize>(v: Vec<T>) -> Result<[T; N], E> {
    let len = v.len();
    v.try_into()
        .map_err(|_| E::invalid_length(len, &Exactly(N)))
}

/// `[f32; N]` from a list of exactly N numbers.
pub fn array<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<[f32; N], D::Error> {
    exact(Vec::<f32>::deserialize(d)?)
}

/// An optional `[f32; N]`, exactly N numbers when present.
pub fn optional_array<'de, D: Deserializer<'de>, const N: usize>(
    d: D,
) -> Result<Option<[f32; N]>, D::Error> {
    Option::<Vec<f32>>::deserialize(d)?.map(exact).transpose()
}

/// An optional list of 2-D vertices, each exactly two numbers.
pub fn optional_vertices<'de, D: Deserializer<'de>>(
    d: D,
) -> Result<Option<Vec<[f64; 2]>>, D::Error> {
    match Option::<Vec<Vec<f64>>>::deserialize(d)? {
        None => Ok(None),
        Some(list) => list
            .into_iter()
            .map(exact)
            .collect::<Result<_, _>>()
            .map(Some),
    }
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

    #[derive(Deserialize, Debug)]
    struct Probe {
        #[serde(deserialize_with = "super::array")]
        p: [f32; 3],
        #[serde(default, deserialize_with = "super::optional_vertices")]
        poly: Option<Vec<[f64; 2]>>,
    }

    #[test]
    fn lists_of_the_wrong_length_are_refused() {
        let ok: Probe = toml::from_str("p = [1, 2, 3]\npoly = [[0, 1], [2, 3]]").unwrap();
        assert_eq!(ok.p, [1.0, 2.0, 3.0]);
        assert_eq!(ok.poly.unwrap().len(), 2);
        for bad in [
            "p = [1, 2, 3, 4]",
            "p = [1, 2]",
            "p = [1, 2, 3]\npoly = [[0, 1, 2]]",
        ] {
            let e = toml::from_str::<Probe>(bad).unwrap_err().to_string();
            assert!(e.contains("exactly"), "{bad}: {e}");
        }
    }
}
