//! How far the vehicle is, for the distance bands: as the flight
//! timeline reads positions (its first usable fix, or its HOME_POSITION
//! once one comes, is the origin; GLOBAL_POSITION_INT not at 0/0, else
//! GPS_RAW_INT with a 2D fix or better), the slant range: the ground
//! distance by haversine and the altitude difference.

use crate::engine::probe::passive::flight::haversine_m;
use crate::frame::{Fix, FixKind, SysComp};

#[derive(Debug, Clone, Copy)]
struct Point {
    lat: f64,
    lon: f64,
    alt: f64,
}

/// The vehicle's last distance from the origin.
#[derive(Debug, Clone, Default)]
pub(crate) struct Whereabouts {
    vehicle: Option<SysComp>,
    origin: Option<Point>,
    /// Its GLOBAL_POSITION_INT came: GPS_RAW_INT is no longer read.
    estimates: bool,
    distance_m: Option<f64>,
}

impl Whereabouts {
    pub(crate) fn distance_m(&self) -> Option<f64> {
        self.distance_m
    }

    pub(crate) fn fix(&mut self, source: SysComp, f: &Fix) {
        if !f.usable(self.estimates) || *self.vehicle.get_or_insert(source) != source {
            return;
        }
        let (lat, lon, alt) = f.degrees();
        let p = Point { lat, lon, alt };
        if f.kind == FixKind::Home {
            self.origin = Some(p);
            return;
        }
        self.estimates |= f.kind == FixKind::Estimate;
        let o = *self.origin.get_or_insert(p);
        let ground = haversine_m((o.lat, o.lon), (p.lat, p.lon));
        self.distance_m = Some(ground.hypot(p.alt - o.alt));
    }
}
