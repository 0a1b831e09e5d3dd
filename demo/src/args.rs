//! A small command-line parser: `--name value` pairs and bare flags after a subcommand.

use std::collections::HashMap;

/// Parsed options of one subcommand.
#[derive(Debug, Default)]
pub struct Args {
    values: HashMap<String, Vec<String>>,
    flags: Vec<String>,
}

/// What went wrong, for the user.
pub type ArgError = String;

impl Args {
    /// Parses `args` (without the program and subcommand names). `flags` lists the options
    /// that take no value; every other `--name` takes the next word, and a few take several
    /// words (everything up to the next `--`), listed in `multi`.
    pub fn parse(args: &[String], flags: &[&str], multi: &[&str]) -> Result<Self, ArgError> {
        let mut out = Args::default();
        let mut i = 0;
        while i < args.len() {
            let a = &args[i];
            let Some(name) = a.strip_prefix("--") else {
                return Err(format!("unexpected argument {a:?} (options start with --)"));
            };
            if flags.contains(&name) {
                out.flags.push(name.to_owned());
                i += 1;
                continue;
            }
            let mut vals = Vec::new();
            i += 1;
            while i < args.len() && !args[i].starts_with("--") {
                vals.push(args[i].clone());
                i += 1;
                if !multi.contains(&name) {
                    break;
                }
            }
            if vals.is_empty() {
                return Err(format!("--{name} needs a value"));
            }
            out.values.entry(name.to_owned()).or_default().extend(vals);
        }
        Ok(out)
    }

    /// Whether bare flag `--name` was given.
    pub fn flag(&self, name: &str) -> bool {
        self.flags.iter().any(|f| f == name)
    }

    /// The value of `--name`, if given (the last one when repeated).
    pub fn get(&self, name: &str) -> Option<&str> {
        self.values
            .get(name)
            .and_then(|v| v.last())
            .map(String::as_str)
    }

    /// All values of `--name`.
    pub fn all(&self, name: &str) -> &[String] {
        self.values.get(name).map_or(&[], Vec::as_slice)
    }

    /// `--name` parsed with `FromStr`, or `default`.
    pub fn parse_or<T: std::str::FromStr>(&self, name: &str, default: T) -> Result<T, ArgError>
    where
        T::Err: std::fmt::Display,
    {
        match self.get(name) {
            None => Ok(default),
            Some(v) => v.parse().map_err(|e| format!("--{name} {v:?}: {e}")),
        }
    }

    /// Fails on any option not in `known`, so that a typo is not silently ignored.
    pub fn reject_unknown(&self, known: &[&str]) -> Result<(), ArgError> {
        let mut unknown: Vec<&String> = self
            .values
            .keys()
            .chain(&self.flags)
            .filter(|n| !known.contains(&n.as_str()))
            .collect();
        if unknown.is_empty() {
            return Ok(());
        }
        unknown.sort();
        let list = |names: &mut dyn Iterator<Item = &str>| {
            names
                .map(|k| format!("--{k}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        Err(format!(
            "unknown option {}; known: {}",
            list(&mut unknown.iter().map(|s| s.as_str())),
            list(&mut known.iter().copied())
        ))
    }
}

/// Parses `WxH` (e.g. `1280x720`); both sides must be at least 1.
pub fn parse_size(s: &str) -> Result<(u32, u32), ArgError> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size {s:?} is not WxH (e.g. 1280x720)"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|n| (1..=16384).contains(n))
            .ok_or_else(|| format!("size {s:?}: {v:?} is not a whole number in 1..=16384"))
    };
    Ok((p(w)?, p(h)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_owned).collect()
    }

    #[test]
    fn values_flags_and_lists() {
        let a = Args::parse(
            &v("--seed 7 --fast --scenes a b c --out x"),
            &["fast"],
            &["scenes"],
        )
        .unwrap();
        assert_eq!(a.get("seed"), Some("7"));
        assert!(a.flag("fast"));
        assert_eq!(a.all("scenes"), ["a", "b", "c"]);
        assert_eq!(a.parse_or("seed", 0u32).unwrap(), 7);
        assert_eq!(a.parse_or("missing", 3u32).unwrap(), 3);
        assert!(a.reject_unknown(&["seed", "fast", "scenes", "out"]).is_ok());
        assert!(a.reject_unknown(&["seed"]).unwrap_err().contains("--fast"));
    }

    #[test]
    fn errors_name_the_option() {
        assert!(
            Args::parse(&v("--seed"), &[], &[])
                .unwrap_err()
                .contains("--seed")
        );
        assert!(Args::parse(&v("seed"), &[], &[]).is_err());
        let a = Args::parse(&v("--seed x"), &[], &[]).unwrap();
        assert!(a.parse_or("seed", 0u32).unwrap_err().contains("--seed"));
    }

    #[test]
    fn sizes() {
        assert_eq!(parse_size("1280x720").unwrap(), (1280, 720));
        assert!(parse_size("0x720").is_err());
        assert!(parse_size("1280").is_err());
        assert!(parse_size("axb").is_err());
    }
}
