//! The C2 link report's headline figures as gauges of the run that made
//! it (`--report c2`): availability, down time, continuity, outages by
//! duration band, the longest outage, and each failsafe model's trips and
//! closest call. All gauges, counts included: each is the latest finished
//! run's figure (a `/probe`'s, a run's at its end), not a count that
//! grows across runs.

use super::exposition::{escape, Exposition, Family, Figure, SeriesFigure};
use super::Metrics;
use crate::engine::c2::{C2Report, FailsafeReplay};

const LINK: [SeriesFigure<C2Report>; 4] = [
    Figure::gauge(
        "mavping_c2_availability_ratio",
        "C2 link report: the share of the run the link was up by the rule (a frame from the vehicle within the up time), 0 to 1; left out before the vehicle was ever heard.",
        |r| Some(r.availability_pct? / 100.0),
    ),
    Figure::gauge(
        "mavping_c2_down_seconds",
        "C2 link report: time the link was down by the rule over the run.",
        |r| Some(r.down_s),
    ),
    Figure::gauge(
        "mavping_c2_continuity_ratio",
        "C2 link report: round trips completed within the continuity time, of those decided, 0 to 1.",
        |r| Some(r.continuity?.pct / 100.0),
    ),
    Figure::gauge(
        "mavping_c2_longest_outage_seconds",
        "C2 link report: the run's longest outage (0 without one).",
        |r| Some(r.outages.longest.first().map_or(0.0, |o| o.duration_s)),
    ),
];

const OUTAGES: Family = Family::gauge(
    "mavping_c2_outages",
    "C2 link report: the run's outages by duration band (<1s, 1-3s, 3-10s, 10-30s, >30s).",
);

const TRIPS: Family = Family::gauge(
    "mavping_c2_failsafe_trips",
    "C2 link report: trips a failsafe model (its preset and setting in labels) would have made on the run's deliveries.",
);

const MARGIN: Family = Family::gauge(
    "mavping_c2_failsafe_closest_margin_seconds",
    "C2 link report: how far the longest wait that did not trip a failsafe model stayed short of its timeout.",
);

/// Every link's C2 link report, where its run made one.
pub(super) fn write_c2(out: &mut Exposition, links: &[&Metrics]) {
    let reports = || {
        links
            .iter()
            .filter_map(|m| Some((m.link_labels(), m.c2.as_deref()?)))
    };
    out.figures(&LINK, reports);
    let bands = reports().flat_map(|(l, r)| {
        let band = move |b: &crate::engine::c2::Band| {
            (format!("{l},band=\"{}\"", escape(b.band)), b.count)
        };
        r.outages.bands.iter().map(band)
    });
    out.family(&OUTAGES, bands);
    // The setting tells two replays of one model (two custom ones) apart.
    let replays = || {
        reports().flat_map(|(l, r)| {
            let labels = move |f: &FailsafeReplay| {
                let (model, setting) = (escape(&f.model), escape(&f.setting));
                format!("{l},model=\"{model}\",setting=\"{setting}\"")
            };
            r.failsafes.iter().map(move |f| (labels(f), f))
        })
    };
    out.family(&TRIPS, replays().map(|(l, f)| (l, f.trips)));
    let margins = replays().filter_map(|(l, f)| Some((l, f.closest_margin_s?)));
    out.family(&MARGIN, margins);
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{has, test_start};
    use super::*;
    use crate::output::runs::c2_report;
    use crate::output::Reporter;

    fn with_report(link: &str, report: Option<C2Report>) -> Metrics {
        let mut m = Metrics::default();
        m.on_start(&test_start(link));
        if let Some(r) = report {
            m.c2_report(link, &r).unwrap();
        }
        m
    }

    #[test]
    fn the_report_as_gauges() {
        insta::assert_snapshot!(with_report("sim:", Some(c2_report())).render());
    }

    /// Each link's series, labelled by it; a link without a report has
    /// none, and no family is written for nothing.
    #[test]
    fn each_link_its_own_series_and_none_without_a_report() {
        let mut other = c2_report();
        other.availability_pct = None;
        other.continuity = None;
        other.outages.longest.clear();
        for f in &mut other.failsafes {
            f.closest_margin_s = None;
        }
        let a = with_report("udp:a", Some(c2_report()));
        let b = with_report("udp:b", Some(other));
        let none = with_report("udp:c", None);
        let text = super::super::render::render(&[&a, &b, &none]);
        has(
            &text,
            r#"mavping_c2_availability_ratio{link="udp:a"} 0.9841666666666667"#,
        );
        has(&text, r#"mavping_c2_down_seconds{link="udp:b"} 9.5"#);
        has(
            &text,
            r#"mavping_c2_longest_outage_seconds{link="udp:b"} 0"#,
        );
        has(&text, r#"mavping_c2_outages{link="udp:b",band="1-3s"} 2"#);
        assert!(!text.contains(r#"mavping_c2_availability_ratio{link="udp:b"}"#));
        assert!(!text.contains(r#"mavping_c2_failsafe_closest_margin_seconds{link="udp:b""#));
        let c2_of_c = |l: &&str| l.starts_with("mavping_c2") && l.contains("udp:c");
        assert!(!text.lines().any(|l| c2_of_c(&l)), "{text}");
        assert_eq!(text.matches("# TYPE mavping_c2_outages gauge").count(), 1);
        assert!(!with_report("udp:c", None).render().contains("mavping_c2"));
    }
}
