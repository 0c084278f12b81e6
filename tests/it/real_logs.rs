//! The real telemetry logs in `../shared/tlogs/` (QGroundControl's,
//! MAVProxy's, ArduPilot SITL's; their README has figures made without
//! mavping), read with `tlog:` and held against a walk of their records by
//! pymavlink's dialect (`tests/peers/tlog_crc_census.py`: per source, the
//! frames whose CRC checks, the damaged ones, the sequence's gaps) and
//! against `mavloss.py`. Read from there, never copied.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

use crate::common::*;
use crate::field_logs::shared_tlog;
use crate::tlog::{mavloss_env, read, tlog};

/// One real log: mavping's summary and the census of its records.
struct Real {
    path: PathBuf,
    summary: Value,
    census: Value,
}

impl Real {
    fn read(name: &str) -> Real {
        let path = shared_tlog(name);
        let out = Command::new(python())
            .arg(peer_script("tlog_crc_census.py"))
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "census: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let census: Value = serde_json::from_slice(&out.stdout).unwrap();
        let (code, summary, err) = read(&["-q"], &tlog(&path));
        assert_eq!(code, 0, "{name}: {err}");
        Real {
            path,
            summary,
            census,
        }
    }

    fn source(&self, id: &str) -> &Value {
        self.summary["sources"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| format!("{}/{}", s["source"]["sysid"], s["source"]["compid"]) == id)
            .unwrap_or_else(|| panic!("no {id} in {}", self.summary["sources"]))
    }

    fn count(&self, id: &str, key: &str) -> u64 {
        self.source(id)["counts"][key].as_u64().unwrap()
    }

    fn census(&self, id: &str, key: &str) -> u64 {
        self.census["sources"][id][key]
            .as_u64()
            .unwrap_or_else(|| panic!("no {key} of {id} in {}", self.census))
    }

    /// Every source the census found a good frame of.
    fn census_sources(&self) -> Vec<String> {
        self.census["sources"]
            .as_object()
            .unwrap()
            .iter()
            .filter(|(_, s)| s["good"].as_u64().unwrap() > 0)
            .map(|(id, _)| id.clone())
            .collect()
    }

    /// Silences of `id` that ended before the log did.
    fn silences(&self, id: &str) -> Vec<&Value> {
        self.source(id)["silences"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| s["ongoing"] == false)
            .collect()
    }

    /// Each source's frames with a good CRC: the census's, and mavloss.py's
    /// (MAVLink 2 on) but where its parser lost a frame after junk.
    fn assert_received(&self, pymavlink_misses: u64) {
        let loss = mavloss_env(&self.path, &[("MAVLINK20", "1")]);
        let mavloss: BTreeMap<String, u64> = loss
            .sources
            .iter()
            .map(|((sys, comp), (count, _))| (format!("{sys}/{comp}"), *count))
            .collect();
        let mut missed = 0;
        for id in self.census_sources() {
            // A frame of an id pymavlink's dialect lacks (PROTOCOL_VERSION
            // in qgc_px4_bench) is one this build may know: received too.
            let good = self.census(&id, "good");
            let unknown = self.census(&id, "unknown");
            assert_eq!(self.count(&id, "received"), good + unknown, "{id}");
            // mavloss.py leaves the SiK radio out, by design.
            if let Some(&m) = mavloss.get(&id) {
                missed += good - m;
            }
        }
        assert_eq!(missed, pymavlink_misses, "mavloss.py {mavloss:?}");
    }
}

/// Pauses of `secs` or more between two records of `source`, by a walk of
/// the records' headers (stamp, then a frame of the length it claims).
fn pauses(path: &Path, source: (u8, u8), secs: f64) -> usize {
    let data = std::fs::read(path).unwrap();
    let (mut at, mut last, mut count) = (0, None::<u64>, 0);
    while at + 8 + 12 <= data.len() {
        let stamp = u64::from_be_bytes(data[at..at + 8].try_into().unwrap());
        let f = &data[at + 8..];
        let (len, ids) = match f[0] {
            0xFE => (8 + usize::from(f[1]), (f[3], f[4])),
            0xFD => (
                12 + usize::from(f[1]) + 13 * usize::from(f[2] & 1),
                (f[5], f[6]),
            ),
            _ => {
                at += 1;
                continue;
            }
        };
        if ids == source {
            if let Some(l) = last {
                count += usize::from((stamp - l) as f64 >= secs * 1e6);
            }
            last = Some(stamp);
        }
        at += 8 + len;
    }
    count
}

#[test]
fn vtol_batches_are_no_silences_and_its_losses_are_never_below_the_sequence() {
    // QGroundControl, whole milliseconds, a batch about once a second.
    let r = Real::read("vtol.tlog");
    r.assert_received(0);
    // Every gap the sequence shows is counted, those across the two
    // outages modulo 256 (738 on short pauses, 234 and 228 across them):
    // pymavlink's own figure here, none of it dropped for a silence.
    assert_eq!(r.count("1/1", "lost"), r.census("1/1", "lost"));
    assert_eq!(r.count("1/1", "lost"), 1_200);
    assert_eq!(r.source("1/1")["pymav"]["loss"], 1_200);
    // The pauses of 2 s or more are its silences: not one per batch.
    let long = pauses(&r.path, (1, 1), 2.0);
    assert_eq!(long, 10);
    let silences = r.silences("1/1");
    let told: Vec<&&Value> = silences
        .iter()
        .filter(|s| s["length_ns"].as_u64().unwrap() >= 2_000_000_000)
        .collect();
    assert_eq!(told.len(), long, "{silences:?}");
    assert!(silences.len() <= long + 2, "{silences:?}");
    // The batch pause is the source's routine (about 1.05 s).
    let routine = r.source("1/1")["routine_pause_ns"].as_u64().unwrap();
    assert!(
        (1_000_000_000..1_300_000_000).contains(&routine),
        "{routine}"
    );
    // The rate is the source's: 115 frames/s, not the 2,100 of a batch.
    let interval = r.source("1/1")["interval_ns"].as_u64().unwrap();
    assert!((7_000_000..11_000_000).contains(&interval), "{interval}");
    // What the wraps may hide is said apart: at most a wrap per long
    // silence that lost any number.
    let extra = r.source("1/1")["silence_frames_estimated"]
        .as_u64()
        .unwrap();
    assert!(extra.is_multiple_of(256) && extra <= 256 * 4, "{extra}");
    // The 4.2 s outage (115 frames/s: about 490 numbers) wrapped.
    let outage = told
        .iter()
        .find(|s| s["length_ns"].as_u64().unwrap() > 4_000_000_000)
        .unwrap();
    assert_eq!(
        (
            outage["seq_lost"].as_u64(),
            outage["lost_estimated"].as_u64()
        ),
        (Some(234), Some(490))
    );
}

#[test]
fn qgc_ardusub_damaged_frames_are_not_lost_and_the_ground_station_is_apart() {
    let r = Real::read("qgc_ardusub_2023-04-18.tlog");
    r.assert_received(0);
    // 1/194's DISTANCE_SENSOR frames fail their CRC against this dialect
    // (pymavlink issue 807): arrived, damaged, filling their numbers.
    assert_eq!(r.count("1/194", "damaged"), r.census("1/194", "damaged"));
    assert_eq!(r.count("1/194", "damaged"), 1_949);
    assert_eq!(
        r.source("1/194")["damaged_ids"],
        serde_json::json!([{"id": 132, "count": 1_949}])
    );
    assert_eq!(r.count("1/194", "lost"), r.census("1/194", "lost"));
    assert!(r.count("1/194", "lost") <= 24, "{}", r.source("1/194"));
    assert_eq!(r.count("1/100", "damaged"), r.census("1/100", "damaged"));
    assert_eq!(r.count("1/1", "lost"), 0);
    // QGroundControl's own frames (255/190, and 255/0 of the same
    // system) are apart: out of the link's figures.
    for gcs in ["255/190", "255/0"] {
        assert_eq!(r.source(gcs)["ground"], true, "{gcs}");
    }
    for vehicle in ["1/1", "1/100", "1/194"] {
        assert_eq!(r.source(vehicle)["ground"], false, "{vehicle}");
    }
    let totals = &r.summary["totals"];
    let vehicle: u64 = ["1/1", "1/100", "1/194"]
        .iter()
        .map(|id| r.census(id, "good"))
        .sum();
    assert_eq!(totals["counts"]["received"], vehicle);
    assert_eq!(
        totals["ground_received"],
        r.census("255/190", "good") + r.census("255/0", "good")
    );
    // Its REQUEST_DATA_STREAM frames are a second counter, read apart:
    // nothing of 255/190 is reordered or duplicate.
    let second = &r.source("255/190")["second_counter"];
    assert_eq!(second["msg_ids"][0]["id"], 66, "{second}");
    // (Read as one counter: 226 reordered and 28 duplicates.)
    let disorder = r.count("255/190", "reordered") + r.count("255/190", "duplicate");
    assert!(disorder <= 5, "{}", r.source("255/190"));
}

#[test]
fn flight_logs_sitl_reboot_is_a_restart_not_a_loss() {
    let r = Real::read("flight_logs.tlog");
    // pymavlink's parser loses frames after junk in this log: 4 of 1/1's
    // and 1 of 250/250's.
    r.assert_received(5);
    let restarts: Vec<&Value> = r
        .silences("1/1")
        .into_iter()
        .filter(|s| s["restart"] == true)
        .collect();
    assert_eq!(restarts.len(), 1, "{:?}", r.silences("1/1"));
    // The census counts the restart's jump to 0 as a gap; mavping does
    // not, and counts every other one.
    let lost = r.count("1/1", "lost");
    assert!(lost < r.census("1/1", "lost"));
    assert!(lost <= 93, "{lost}");
    assert_eq!(r.source("250/250")["ground"], true);
    assert_eq!(
        r.summary["totals"]["counts"]["received"],
        r.census("1/1", "good")
    );
}

#[test]
fn qgc_px4_bench_and_ardusub_gps_vehicles_lose_nothing() {
    let r = Real::read("qgc_px4_bench_2019-11-20.tlog");
    // mavloss.py's parser loses one of 1/1's frames at the switch from
    // MAVLink 1 to 2 ("Bad prefix").
    r.assert_received(1);
    assert_eq!(r.count("1/1", "lost"), 0);
    assert_eq!(r.source("255/0")["ground"], true);
    let r = Real::read("qgc_ardusub_gps_2023-05-04.tlog");
    r.assert_received(0);
    assert_eq!(r.count("1/1", "lost"), 0);
    assert_eq!(r.count("1/100", "damaged"), 4);
    assert_eq!(r.count("1/100", "lost"), 0);
    assert_eq!(r.source("255/190")["ground"], true);
}
