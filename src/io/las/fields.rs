//! The standard fields of a LAS point record as the cloud's scalar fields, under laspy's names,
//! each holding the record's own integer (or, for GPS time and the waveform's floats, its own
//! number), so that a record written back is the record read.

use las::raw::point::{Flags, Waveform};
use las::raw::Point as RawPoint;

/// A standard field of a point record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Std {
    Intensity,
    ReturnNumber,
    NumberOfReturns,
    ScanDirectionFlag,
    EdgeOfFlightLine,
    Classification,
    Synthetic,
    KeyPoint,
    Withheld,
    /// Point formats 6-10 only (in 0-5 "overlap" is class 12).
    Overlap,
    ScannerChannel,
    /// Point formats 0-5: whole degrees, `i8`.
    ScanAngleRank,
    /// Point formats 6-10: units of 0.006°, `i16`.
    ScanAngle,
    UserData,
    PointSourceId,
    GpsTime,
    Red,
    Green,
    Blue,
    Nir,
    WavepacketIndex,
    WavepacketOffset,
    WavepacketSize,
    ReturnPointWaveLocation,
    Xt,
    Yt,
    Zt,
}

use Std::*;

/// Every standard field, in laspy's order.
pub(super) const ALL: [Std; 27] = [
    Intensity,
    ReturnNumber,
    NumberOfReturns,
    Synthetic,
    KeyPoint,
    Withheld,
    Overlap,
    ScannerChannel,
    ScanDirectionFlag,
    EdgeOfFlightLine,
    Classification,
    ScanAngleRank,
    UserData,
    ScanAngle,
    PointSourceId,
    GpsTime,
    Red,
    Green,
    Blue,
    Nir,
    WavepacketIndex,
    WavepacketOffset,
    WavepacketSize,
    ReturnPointWaveLocation,
    Xt,
    Yt,
    Zt,
];

/// What a point format holds beyond x y z and the fields every format has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(super) struct Caps {
    pub extended: bool,
    pub gps: bool,
    pub rgb: bool,
    pub nir: bool,
    pub waveform: bool,
}

impl Caps {
    /// The capabilities of point format `f` (0-10).
    pub fn of(f: u8) -> Caps {
        Caps {
            extended: f >= 6,
            gps: f != 0 && f != 2,
            rgb: matches!(f, 2 | 3 | 5 | 7 | 8 | 10),
            nir: matches!(f, 8 | 10),
            waveform: matches!(f, 4 | 5 | 9 | 10),
        }
    }

    /// The smallest point format that holds all of `self`.
    pub fn format(self) -> u8 {
        (0..=10)
            .find(|&f| {
                let c = Caps::of(f);
                (c.extended || !self.extended)
                    && (c.gps || !self.gps)
                    && (c.rgb || !self.rgb)
                    && (c.nir || !self.nir)
                    && (c.waveform || !self.waveform)
            })
            .unwrap_or(10)
    }

    /// The union of two sets of capabilities.
    pub fn with(self, o: Caps) -> Caps {
        Caps {
            extended: self.extended || o.extended,
            gps: self.gps || o.gps,
            rgb: self.rgb || o.rgb,
            nir: self.nir || o.nir,
            waveform: self.waveform || o.waveform,
        }
    }
}

impl Std {
    /// laspy's name, which the cloud's scalar field takes.
    pub fn name(self) -> &'static str {
        match self {
            Intensity => "intensity",
            ReturnNumber => "return_number",
            NumberOfReturns => "number_of_returns",
            ScanDirectionFlag => "scan_direction_flag",
            EdgeOfFlightLine => "edge_of_flight_line",
            Classification => "classification",
            Synthetic => "synthetic",
            KeyPoint => "key_point",
            Withheld => "withheld",
            Overlap => "overlap",
            ScannerChannel => "scanner_channel",
            ScanAngleRank => "scan_angle_rank",
            ScanAngle => "scan_angle",
            UserData => "user_data",
            PointSourceId => "point_source_id",
            GpsTime => "gps_time",
            Red => "red",
            Green => "green",
            Blue => "blue",
            Nir => "nir",
            WavepacketIndex => "wavepacket_index",
            WavepacketOffset => "wavepacket_offset",
            WavepacketSize => "wavepacket_size",
            ReturnPointWaveLocation => "return_point_wave_location",
            Xt => "x_t",
            Yt => "y_t",
            Zt => "z_t",
        }
    }

    /// The field of this name, if any.
    pub fn named(name: &str) -> Option<Std> {
        ALL.into_iter().find(|s| s.name() == name)
    }

    /// Whether a record of a format with `caps` has this field.
    pub fn in_format(self, caps: Caps) -> bool {
        match self {
            Overlap | ScannerChannel | ScanAngle => caps.extended,
            ScanAngleRank => !caps.extended,
            GpsTime => caps.gps,
            Red | Green | Blue => caps.rgb,
            Nir => caps.nir,
            WavepacketIndex
            | WavepacketOffset
            | WavepacketSize
            | ReturnPointWaveLocation
            | Xt
            | Yt
            | Zt => caps.waveform,
            _ => true,
        }
    }

    /// What the cloud must hold for this field to be read even when every point has 0:
    /// `intensity` and `classification` always, and the fields a format adds (GPS time,
    /// colour, NIR, waveform).
    pub fn always_kept(self) -> bool {
        !matches!(
            self,
            ReturnNumber
                | NumberOfReturns
                | ScanDirectionFlag
                | EdgeOfFlightLine
                | Synthetic
                | KeyPoint
                | Withheld
                | Overlap
                | ScannerChannel
                | ScanAngleRank
                | ScanAngle
                | UserData
                | PointSourceId
        )
    }

    /// The values a record of a format with `caps` holds, as (smallest, largest); `None` for
    /// GPS time and the waveform's floats, which take any number.
    pub fn range(self, caps: Caps) -> Option<(f64, f64)> {
        let bits = |b: u32| Some((0.0, ((1u64 << b) - 1) as f64));
        match self {
            Intensity | PointSourceId | Red | Green | Blue | Nir => bits(16),
            ReturnNumber | NumberOfReturns => bits(if caps.extended { 4 } else { 3 }),
            Classification => bits(if caps.extended { 8 } else { 5 }),
            ScanDirectionFlag | EdgeOfFlightLine | Synthetic | KeyPoint | Withheld | Overlap => {
                bits(1)
            }
            ScannerChannel => bits(2),
            ScanAngleRank => Some((-128.0, 127.0)),
            ScanAngle => Some((-32768.0, 32767.0)),
            UserData | WavepacketIndex => bits(8),
            WavepacketSize => bits(32),
            WavepacketOffset => Some((0.0, 2f64.powi(53))),
            GpsTime | ReturnPointWaveLocation | Xt | Yt | Zt => None,
        }
    }

    /// Whether every value of `values` is one the field holds in a format with `caps`.
    pub fn holds(self, caps: Caps, values: &[f64]) -> bool {
        match self.range(caps) {
            None if matches!(self, GpsTime) => true,
            // The waveform's floats are f32.
            None => values.iter().all(|&v| v.is_nan() || v as f32 as f64 == v),
            Some((lo, hi)) => values
                .iter()
                .all(|&v| (lo..=hi).contains(&v) && v.fract() == 0.0),
        }
    }

    /// This field of the record `p`.
    pub fn get(self, p: &RawPoint) -> f64 {
        let (a, b, c) = match p.flags {
            Flags::TwoByte(a, b) => (a, b, 0),
            Flags::ThreeByte(a, b, c) => (a, b, c),
        };
        let ext = matches!(p.flags, Flags::ThreeByte(..));
        let bit = |byte: u8, k: u32| f64::from((byte >> k) & 1);
        let w = p.waveform.unwrap_or_default();
        let rgb = p.color.unwrap_or_default();
        match self {
            Intensity => f64::from(p.intensity),
            ReturnNumber if ext => f64::from(a & 15),
            ReturnNumber => f64::from(a & 7),
            NumberOfReturns if ext => f64::from(a >> 4),
            NumberOfReturns => f64::from((a >> 3) & 7),
            ScanDirectionFlag if ext => bit(b, 6),
            ScanDirectionFlag => bit(a, 6),
            EdgeOfFlightLine if ext => bit(b, 7),
            EdgeOfFlightLine => bit(a, 7),
            Classification if ext => f64::from(c),
            Classification => f64::from(b & 31),
            Synthetic if ext => bit(b, 0),
            Synthetic => bit(b, 5),
            KeyPoint if ext => bit(b, 1),
            KeyPoint => bit(b, 6),
            Withheld if ext => bit(b, 2),
            Withheld => bit(b, 7),
            Overlap => bit(b, 3),
            ScannerChannel => f64::from((b >> 4) & 3),
            ScanAngleRank | ScanAngle => match p.scan_angle {
                las::raw::point::ScanAngle::Rank(r) => f64::from(r),
                las::raw::point::ScanAngle::Scaled(s) => f64::from(s),
            },
            UserData => f64::from(p.user_data),
            PointSourceId => f64::from(p.point_source_id),
            GpsTime => p.gps_time.unwrap_or(0.0),
            Red => f64::from(rgb.red),
            Green => f64::from(rgb.green),
            Blue => f64::from(rgb.blue),
            Nir => f64::from(p.nir.unwrap_or(0)),
            WavepacketIndex => f64::from(w.wave_packet_descriptor_index),
            WavepacketOffset => w.byte_offset_to_waveform_data as f64,
            WavepacketSize => f64::from(w.waveform_packet_size_in_bytes),
            ReturnPointWaveLocation => f64::from(w.return_point_waveform_location),
            Xt => f64::from(w.x_t),
            Yt => f64::from(w.y_t),
            Zt => f64::from(w.z_t),
        }
    }
}

/// The standard fields of one point as values (0 for a field the cloud does not have), to be
/// packed into a record of a format with `caps`. Values are checked by [`Std::holds`] first.
pub(super) fn record(caps: Caps, value: impl Fn(Std) -> f64) -> RawPoint {
    let u = |s: Std| value(s) as u64 as u8;
    let flag = |s: Std, k: u32| (value(s) as u8 & 1) << k;
    let flags = if caps.extended {
        let a = u(ReturnNumber) | u(NumberOfReturns) << 4;
        let b = flag(Synthetic, 0)
            | flag(KeyPoint, 1)
            | flag(Withheld, 2)
            | flag(Overlap, 3)
            | (u(ScannerChannel) & 3) << 4
            | flag(ScanDirectionFlag, 6)
            | flag(EdgeOfFlightLine, 7);
        Flags::ThreeByte(a, b, u(Classification))
    } else {
        let a = (u(ReturnNumber) & 7)
            | (u(NumberOfReturns) & 7) << 3
            | flag(ScanDirectionFlag, 6)
            | flag(EdgeOfFlightLine, 7);
        let b =
            (u(Classification) & 31) | flag(Synthetic, 5) | flag(KeyPoint, 6) | flag(Withheld, 7);
        Flags::TwoByte(a, b)
    };
    let u16_of = |s: Std| value(s) as u16;
    RawPoint {
        intensity: u16_of(Intensity),
        flags,
        scan_angle: if caps.extended {
            las::raw::point::ScanAngle::Scaled(value(ScanAngle) as i16)
        } else {
            las::raw::point::ScanAngle::Rank(value(ScanAngleRank) as i8)
        },
        user_data: u(UserData),
        point_source_id: u16_of(PointSourceId),
        gps_time: caps.gps.then(|| value(GpsTime)),
        color: caps
            .rgb
            .then(|| las::Color::new(u16_of(Red), u16_of(Green), u16_of(Blue))),
        nir: caps.nir.then(|| u16_of(Nir)),
        waveform: caps.waveform.then(|| Waveform {
            wave_packet_descriptor_index: u(WavepacketIndex),
            byte_offset_to_waveform_data: value(WavepacketOffset) as u64,
            waveform_packet_size_in_bytes: value(WavepacketSize) as u32,
            return_point_waveform_location: value(ReturnPointWaveLocation) as f32,
            x_t: value(Xt) as f32,
            y_t: value(Yt) as f32,
            z_t: value(Zt) as f32,
        }),
        ..RawPoint::default()
    }
}
