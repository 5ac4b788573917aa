//! UTC times for GPX (`xsd:dateTime`): parsing `--utc-start` and formatting
//! `utc_start + stamp`, without a calendar crate (proleptic Gregorian
//! calendar, no leap seconds, as RFC 3339 and Unix time).

/// A UTC instant, ns since 1970-01-01T00:00:00Z.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct UtcTime {
    /// ns since the Unix epoch.
    pub unix_ns: i128,
}

impl UtcTime {
    /// Parses RFC 3339: `2026-06-21T09:30:00Z`, `2026-06-21T09:30:00.250+01:00`
    /// (a space may replace the `T`).
    pub fn parse(text: &str) -> Result<UtcTime, String> {
        let bad = || format!("{text:?} is not an RFC 3339 time such as 2026-06-21T09:30:00Z");
        let s = text.trim();
        let b = s.as_bytes();
        if b.len() < 20 || b[4] != b'-' || b[7] != b'-' || b[13] != b':' || b[16] != b':' {
            return Err(bad());
        }
        if !matches!(b[10], b'T' | b't' | b' ') {
            return Err(bad());
        }
        let num = |r: std::ops::Range<usize>| -> Result<i64, String> {
            let part = s.get(r).ok_or_else(bad)?;
            if !part.bytes().all(|c| c.is_ascii_digit()) {
                return Err(bad());
            }
            part.parse::<i64>().map_err(|_| bad())
        };
        let (year, month, day) = (num(0..4)?, num(5..7)?, num(8..10)?);
        let (hour, minute, second) = (num(11..13)?, num(14..16)?, num(17..19)?);
        if !(1..=12).contains(&month)
            || day < 1
            || day > days_in_month(year, month)
            || hour > 23
            || minute > 59
            || second > 60
        {
            return Err(bad());
        }
        let mut i = 19;
        let mut frac_ns: i64 = 0;
        if b.get(i) == Some(&b'.') {
            i += 1;
            let start = i;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            if i == start {
                return Err(bad());
            }
            let digits = &s[start..i.min(start + 9)];
            frac_ns =
                digits.parse::<i64>().map_err(|_| bad())? * 10i64.pow(9 - digits.len() as u32);
        }
        let offset_s: i64 = match s.get(i..) {
            Some("Z" | "z") => 0,
            Some(tz) if tz.len() == 6 && (tz.starts_with('+') || tz.starts_with('-')) => {
                let h = num(i + 1..i + 3)?;
                if b[i + 3] != b':' {
                    return Err(bad());
                }
                let m = num(i + 4..i + 6)?;
                if h > 23 || m > 59 {
                    return Err(bad());
                }
                let sign = if tz.starts_with('-') { -1 } else { 1 };
                sign * (h * 3600 + m * 60)
            }
            _ => return Err(bad()),
        };
        let days = days_from_civil(year, month, day);
        let secs = days * 86_400 + hour * 3600 + minute * 60 + second - offset_s;
        Ok(UtcTime {
            unix_ns: secs as i128 * 1_000_000_000 + frac_ns as i128,
        })
    }

    /// This instant plus `ns`.
    pub fn plus_ns(self, ns: u64) -> UtcTime {
        UtcTime {
            unix_ns: self.unix_ns + ns as i128,
        }
    }

    /// RFC 3339 in UTC with milliseconds: `2026-06-21T09:30:00.250Z`.
    pub fn to_rfc3339_millis(self) -> String {
        let ms = self.unix_ns.div_euclid(1_000_000);
        let secs = ms.div_euclid(1000);
        let millis = ms.rem_euclid(1000);
        let days = secs.div_euclid(86_400) as i64;
        let sod = secs.rem_euclid(86_400) as i64;
        let (y, m, d) = civil_from_days(days);
        format!(
            "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}.{millis:03}Z",
            sod / 3600,
            sod / 60 % 60,
            sod % 60
        )
    }
}

fn is_leap(y: i64) -> bool {
    (y % 4 == 0 && y % 100 != 0) || y % 400 == 0
}

fn days_in_month(y: i64, m: i64) -> i64 {
    match m {
        2 if is_leap(y) => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// Days since 1970-01-01 of a civil date (H. Hinnant's `days_from_civil`).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The civil date of a day count since 1970-01-01 (inverse of the above).
fn civil_from_days(z: i64) -> (i64, i64, i64) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + if m <= 2 { 1 } else { 0 };
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_instants() {
        let t = UtcTime::parse("1970-01-01T00:00:00Z").expect("epoch");
        assert_eq!(t.unix_ns, 0);
        // `date -u -d 2026-06-21T09:30:00Z +%s` = 1782034200
        let t = UtcTime::parse("2026-06-21T09:30:00Z").expect("parse");
        assert_eq!(t.unix_ns, 1_782_034_200 * 1_000_000_000);
        let t2 = UtcTime::parse("2026-06-21T10:30:00.5+01:00").expect("offset");
        assert_eq!(t2.unix_ns, t.unix_ns + 500_000_000);
        assert_eq!(
            t.plus_ns(86_400_000_000_000 + 1_250_000_000)
                .to_rfc3339_millis(),
            "2026-06-22T09:30:01.250Z"
        );
        assert_eq!(
            UtcTime::parse("2024-02-29 23:59:59.999Z")
                .expect("leap day")
                .to_rfc3339_millis(),
            "2024-02-29T23:59:59.999Z"
        );
    }

    #[test]
    fn bad_times_are_errors() {
        for s in [
            "",
            "2026-06-21",
            "2026-13-01T00:00:00Z",
            "2025-02-29T00:00:00Z",
            "2026-06-21T09:30:00",
            "2026-06-21T09:30:00.Z",
            "2026-06-21T24:00:00Z",
            "2026-06-21T09:30:00+1:00",
            "２０２６-06-21T09:30:00Z",
        ] {
            assert!(UtcTime::parse(s).is_err(), "{s:?} parsed");
        }
    }

    #[test]
    fn calendar_round_trips() {
        for days in (-800_000i64..800_000).step_by(997) {
            let (y, m, d) = civil_from_days(days);
            assert_eq!(days_from_civil(y, m, d), days);
        }
    }
}
