//! `--budget cpu=2%,ram=4k,flash=64k`: what a clip may take of its chip.

use std::fmt;
use std::str::FromStr;

use super::cost::Cost;

/// Limits on a clip's cost; `None` is no limit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Budget {
    /// Share of the core (0.02 = 2 %).
    pub cpu: Option<f64>,
    /// State + pose + playback stack, bytes.
    pub ram: Option<usize>,
    /// Clip + decoder code, bytes.
    pub flash: Option<usize>,
}

/// A budget that does not parse.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BudgetError {
    #[error("budget item '{0}' is not NAME=VALUE (cpu=2%, ram=4k, flash=64k)")]
    Item(String),
    #[error("unknown budget '{0}' (cpu, ram, flash)")]
    Name(String),
    #[error("cpu budget '{0}' is not a percentage above 0 and at most 100 (e.g. 2%)")]
    Cpu(String),
    #[error("{0} budget '{1}' is not a size in bytes (e.g. 4096, 4k, 1m)")]
    Size(&'static str, String),
    #[error("budget '{0}' is given twice")]
    Twice(String),
}

impl FromStr for Budget {
    type Err = BudgetError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let mut b = Budget::default();
        for item in s.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let (name, value) = item
                .split_once('=')
                .ok_or_else(|| BudgetError::Item(item.to_string()))?;
            let (name, value) = (name.trim(), value.trim());
            let twice = || BudgetError::Twice(name.to_string());
            match name {
                "cpu" => {
                    let v = value.strip_suffix('%').unwrap_or(value).trim();
                    let p: f64 = v.parse().map_err(|_| BudgetError::Cpu(value.into()))?;
                    if !(p > 0.0 && p <= 100.0) {
                        return Err(BudgetError::Cpu(value.into()));
                    }
                    if b.cpu.replace(p / 100.0).is_some() {
                        return Err(twice());
                    }
                }
                "ram" => {
                    if b.ram.replace(size("ram", value)?).is_some() {
                        return Err(twice());
                    }
                }
                "flash" => {
                    if b.flash.replace(size("flash", value)?).is_some() {
                        return Err(twice());
                    }
                }
                _ => return Err(BudgetError::Name(name.to_string())),
            }
        }
        Ok(b)
    }
}

/// `4096`, `4k`, `4K`, `4kb`, `1m`: bytes (k = 1024).
fn size(what: &'static str, s: &str) -> Result<usize, BudgetError> {
    let err = || BudgetError::Size(what, s.to_string());
    let lower = s.to_ascii_lowercase();
    let t = lower.strip_suffix('b').unwrap_or(&lower);
    let (digits, scale) = match t.as_bytes().last() {
        Some(b'k') => (&t[..t.len() - 1], 1024),
        Some(b'm') => (&t[..t.len() - 1], 1024 * 1024),
        _ => (t, 1),
    };
    let v: f64 = digits.trim().parse().map_err(|_| err())?;
    if !(v.is_finite() && v >= 0.0) {
        return Err(err());
    }
    Ok((v * scale as f64).round() as usize)
}

impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = Vec::new();
        if let Some(c) = self.cpu {
            parts.push(format!("cpu={}%", c * 100.0));
        }
        if let Some(r) = self.ram {
            parts.push(format!("ram={r}"));
        }
        if let Some(fl) = self.flash {
            parts.push(format!("flash={fl}"));
        }
        if parts.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&parts.join(","))
        }
    }
}

impl Budget {
    /// What of `cost` goes over the budget (or over the chip: its flash
    /// and RAM are a budget of their own); empty when it fits.
    pub fn overruns(&self, cost: &Cost) -> Vec<String> {
        let mut out = Vec::new();
        let chip = cost.chip;
        if let Some(cpu) = self.cpu {
            if cost.cpu_share > cpu {
                out.push(format!(
                    "cpu {:.2}% > {:.2}%",
                    cost.cpu_share * 100.0,
                    cpu * 100.0
                ));
            }
        }
        if cost.cpu_share > 1.0 {
            out.push(format!(
                "cpu {:.0}% of the {}: not in real time",
                cost.cpu_share * 100.0,
                chip.name
            ));
        }
        let ram = cost.ram_bytes();
        let ram_limit = self.ram.unwrap_or(usize::MAX).min(chip.ram_bytes as usize);
        if ram > ram_limit {
            out.push(format!("ram {ram} B > {ram_limit} B"));
        }
        let flash_limit = self
            .flash
            .unwrap_or(usize::MAX)
            .min(chip.flash_bytes as usize);
        if cost.flash_bytes > flash_limit {
            out.push(format!("flash {} B > {flash_limit} B", cost.flash_bytes));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_form() {
        let b: Budget = "cpu=2%,ram=4k,flash=1.5m".parse().unwrap();
        assert_eq!(b.cpu, Some(0.02));
        assert_eq!(b.ram, Some(4096));
        assert_eq!(b.flash, Some(1_572_864));
        let b: Budget = " ram = 2048B ".parse().unwrap();
        assert_eq!((b.cpu, b.ram, b.flash), (None, Some(2048), None));
        assert_eq!("cpu=0.5".parse::<Budget>().unwrap().cpu, Some(0.005));
    }

    #[test]
    fn refuses_what_is_not_a_budget() {
        assert_eq!(
            "cpu".parse::<Budget>(),
            Err(BudgetError::Item("cpu".into()))
        );
        assert_eq!(
            "gpu=2%".parse::<Budget>(),
            Err(BudgetError::Name("gpu".into()))
        );
        assert_eq!(
            "cpu=0%".parse::<Budget>(),
            Err(BudgetError::Cpu("0%".into()))
        );
        assert_eq!(
            "cpu=120%".parse::<Budget>(),
            Err(BudgetError::Cpu("120%".into()))
        );
        assert_eq!(
            "ram=lots".parse::<Budget>(),
            Err(BudgetError::Size("ram", "lots".into()))
        );
        assert_eq!(
            "ram=1k,ram=2k".parse::<Budget>(),
            Err(BudgetError::Twice("ram".into()))
        );
        assert!("ram=-1k".parse::<Budget>().is_err());
    }
}
