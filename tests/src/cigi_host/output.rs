//! What a host run printed: one JSON object per line (`tests/cigi-host/README.md` lists them),
//! ending with its summary.

use serde_json::Value;

/// The parsed lines of one host run.
#[derive(Debug, Clone)]
pub struct HostOutput {
    pub lines: Vec<Value>,
}

impl HostOutput {
    /// Parses the host's stdout; `Err` names the first line that is not a JSON object.
    pub fn parse(stdout: &str) -> Result<Self, String> {
        let mut lines = Vec::new();
        for (i, l) in stdout.lines().enumerate() {
            let v: Value = serde_json::from_str(l)
                .map_err(|e| format!("host stdout line {}: {e}: {l:?}", i + 1))?;
            if !v.is_object() {
                return Err(format!("host stdout line {}: not an object: {l:?}", i + 1));
            }
            lines.push(v);
        }
        Ok(Self { lines })
    }

    /// Lines recording what was sent, of kind `what` ("msg", "hot_req", "los_seg", "los_vect").
    pub fn sent<'a>(&'a self, what: &'a str) -> impl Iterator<Item = &'a Value> + 'a {
        self.lines.iter().filter(move |l| l["sent"] == what)
    }

    /// Lines recording what was received, of kind `what` ("sof", "hot", "hotx", "los", "losx",
    /// "error").
    pub fn recv<'a>(&'a self, what: &'a str) -> impl Iterator<Item = &'a Value> + 'a {
        self.lines.iter().filter(move |l| l["recv"] == what)
    }

    /// Every response (any of 102–105) to request `id`, in arrival order.
    pub fn responses(&self, id: u64) -> Vec<&Value> {
        self.lines
            .iter()
            .filter(|l| l.get("recv").is_some() && l["id"] == id)
            .collect()
    }

    /// The closing summary line.
    pub fn summary(&self) -> Option<&Value> {
        self.lines.iter().rev().find(|l| l.get("summary").is_some())
    }
}
