//! HDF5 output: the ROM file (`nlrom reduce`) and the results file (`nlrom solve`, `march`, `run`).
//!
//! * [`h5`]: a small, format-level layer — an in-memory tree of groups, datasets (f64, i64, u64,
//!   complex as compound `{r, i}`, compound records, strings) and attributes, written atomically,
//!   and a reader for what it writes.
//! * [`rom_file`]: [`write_rom`] / [`read_rom`], the `/rom/` layout of `docs/results-file.md`.
//! * [`results`]: the data types the solvers fill ([`ResultsFile`], [`FrfData`], [`ContactData`],
//!   [`MarchData`]) and [`write_results`] / [`read_results`], the `/frf/`, `/contact/`, `/march/`
//!   layout of `docs/results-file.md`.
//!
//! Every file carries the root attributes of `docs/results-file.md` ([`file_attributes`]): `program`
//! (`"nlrom"`), `version` (the crate version), `file_kind` (`"rom"` or `"results"`), `title`,
//! `case_text` (the case file text) and `created` (UTC, ISO 8601). Every dataset carries `unit` and
//! `description` (`docs/conventions.md` §5). The layout is documented dataset by dataset in
//! `docs/results-file.md`.

pub mod h5;
pub mod results;
pub mod rom_file;

use std::time::{SystemTime, UNIX_EPOCH};

pub use h5::{Attr, Column, Data, Dataset, Group, H5File, H5Reader, Records};
pub use results::{
    read_results, write_results, ContactCurveDetail, ContactData, ContactMap, ContactPairData,
    FrfData, FrfRecord, MarchData, PointLoops, ResponseDof, ResultsFile,
};
pub use rom_file::{read_rom, write_rom};

use crate::error::Result;

/// Value of the root attribute `program`.
pub const PROGRAM: &str = "nlrom";

/// What every nlrom file records about the case it came from.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FileInfo {
    /// The case title (`title` of the case file; may be empty).
    pub title: String,
    /// The full text of the case file (may be empty when no case file was used).
    pub case_text: String,
}

/// The root attributes of an nlrom file of kind `file_kind` (`"rom"` or `"results"`): `program`,
/// `version`, `file_kind`, `title`, `case_text`, `created`.
pub fn file_attributes(info: &FileInfo, file_kind: &str) -> Group {
    let mut root = Group::default();
    root.set_attr("program", Attr::Str(PROGRAM.to_string()))
        .set_attr("version", Attr::Str(env!("CARGO_PKG_VERSION").to_string()))
        .set_attr("file_kind", Attr::Str(file_kind.to_string()))
        .set_attr("title", Attr::Str(info.title.clone()))
        .set_attr("case_text", Attr::Str(info.case_text.clone()))
        .set_attr("created", Attr::Str(utc_now()));
    root
}

/// Checks that the file read by `reader` is an nlrom file of kind `file_kind` and returns its
/// [`FileInfo`]; the error names the file.
pub fn check_file_kind(reader: &H5Reader, file_kind: &str) -> Result<FileInfo> {
    let root = reader.group("/")?;
    let attr = |name: &str| root.attrs.get(name).and_then(Attr::as_str);
    if attr("program") != Some(PROGRAM) {
        return Err(reader.error(
            "/",
            format!("not an nlrom file (no root attribute program = \"{PROGRAM}\")"),
        ));
    }
    if attr("file_kind") != Some(file_kind) {
        return Err(reader.error(
            "/",
            format!(
                "an nlrom {} file, expected a {file_kind} file",
                attr("file_kind").unwrap_or("unknown")
            ),
        ));
    }
    Ok(FileInfo {
        title: attr("title").unwrap_or_default().to_string(),
        case_text: attr("case_text").unwrap_or_default().to_string(),
    })
}

/// The current time, UTC, as `YYYY-MM-DDThh:mm:ssZ`.
pub fn utc_now() -> String {
    let seconds = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_timestamp(seconds)
}

/// `seconds` since 1970-01-01T00:00:00Z as `YYYY-MM-DDThh:mm:ssZ` (proleptic Gregorian calendar;
/// days to civil date after H. Hinnant, "chrono-Compatible Low-Level Date Algorithms").
pub fn utc_timestamp(seconds: u64) -> String {
    let days = (seconds / 86_400) as i64;
    let rem = seconds % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::utc_timestamp;

    /// Reference values from `date -u -d @SECONDS +%FT%TZ`.
    #[test]
    fn timestamps_match_gnu_date() {
        assert_eq!(utc_timestamp(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_timestamp(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc_timestamp(1_795_000_000), "2026-11-18T11:06:40Z");
        assert_eq!(utc_timestamp(4_107_542_399), "2100-02-28T23:59:59Z");
    }
}
