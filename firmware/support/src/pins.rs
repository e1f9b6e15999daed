//! The board's analogue inputs: the pin each sensor is wired to and the ADC
//! and channel that read it, checked against the part's datasheet, at
//! compile time ([`MAP_IS_WIRED`]) and by the tests.
//!
//! ```
//! use finrs_firmware_support::pins::{self, Pin, Input};
//!
//! assert!(pins::MAP_IS_WIRED);
//! // PB1 is ADC12_IN9: ADC2 reads it, ADC3 cannot.
//! assert!(pins::on_datasheet(Input { pin: Pin::new(b'B', 1), adc: 2, channel: 9 }));
//! assert!(!pins::on_datasheet(Input { pin: Pin::new(b'B', 1), adc: 3, channel: 9 }));
//! ```

/// A GPIO pin: port letter and number, e.g. `PB1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pin {
    /// Port, `b'A'` ..
    pub port: u8,
    /// Pin number, 0..=15.
    pub number: u8,
}

impl Pin {
    /// `P{port}{number}`.
    pub const fn new(port: u8, number: u8) -> Self {
        Self { port, number }
    }

    /// Whether this is `P{port}{number}` (`==` is not `const`).
    pub const fn is(self, port: u8, number: u8) -> bool {
        self.port == port && self.number == number
    }
}

/// An analogue input as wired: the pin, the ADC (1, 2 or 3) that converts
/// it and the channel it is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Input {
    /// The pin.
    pub pin: Pin,
    /// ADC1, ADC2 or ADC3.
    pub adc: u8,
    /// The ADC channel, `INx`.
    pub channel: u8,
}

/// The analogue inputs of the STM32F407VG's package (LQFP100), as the
/// datasheet lists them (DS8626, table "STM32F40xxx pin and ball
/// definitions", additional functions): the pin, which ADCs reach it (bit
/// `k - 1` for ADCk: `ADC123_INx` is `0b111`, `ADC12_INx` `0b011`) and the
/// channel. ADC3's other inputs (IN4..IN9, IN14, IN15) are on port F, which
/// this package does not have.
pub const DATASHEET_LQFP100: [(Pin, u8, u8); 16] = [
    (Pin::new(b'A', 0), 0b111, 0),
    (Pin::new(b'A', 1), 0b111, 1),
    (Pin::new(b'A', 2), 0b111, 2),
    (Pin::new(b'A', 3), 0b111, 3),
    (Pin::new(b'A', 4), 0b011, 4),
    (Pin::new(b'A', 5), 0b011, 5),
    (Pin::new(b'A', 6), 0b011, 6),
    (Pin::new(b'A', 7), 0b011, 7),
    (Pin::new(b'B', 0), 0b011, 8),
    (Pin::new(b'B', 1), 0b011, 9),
    (Pin::new(b'C', 0), 0b111, 10),
    (Pin::new(b'C', 1), 0b111, 11),
    (Pin::new(b'C', 2), 0b111, 12),
    (Pin::new(b'C', 3), 0b111, 13),
    (Pin::new(b'C', 4), 0b011, 14),
    (Pin::new(b'C', 5), 0b011, 15),
];

/// The load cell's amplifier: PA1, ADC1 IN1 (first of ADC1's group).
pub const LOAD_CELL: Input = Input {
    pin: Pin::new(b'A', 1),
    adc: 1,
    channel: 1,
};

/// The shunt amplifiers of segments 0..=7. ADC1 takes segments 0..=2 after
/// the load cell, ADC2 3..=6 and ADC3 7 ([`adc_of_segment`]); ADC3 reaches
/// only PA0..PA3 and PC0..PC3 on this package, so segment 7 is on PC2
/// (IN12) and segment 3, on ADC2, on PB1 (IN9).
pub const SHUNTS: [Input; 8] = [
    Input {
        pin: Pin::new(b'A', 2),
        adc: 1,
        channel: 2,
    },
    Input {
        pin: Pin::new(b'A', 3),
        adc: 1,
        channel: 3,
    },
    Input {
        pin: Pin::new(b'C', 1),
        adc: 1,
        channel: 11,
    },
    Input {
        pin: Pin::new(b'B', 1),
        adc: 2,
        channel: 9,
    },
    Input {
        pin: Pin::new(b'C', 4),
        adc: 2,
        channel: 14,
    },
    Input {
        pin: Pin::new(b'C', 5),
        adc: 2,
        channel: 15,
    },
    Input {
        pin: Pin::new(b'B', 0),
        adc: 2,
        channel: 8,
    },
    Input {
        pin: Pin::new(b'C', 2),
        adc: 3,
        channel: 12,
    },
];

/// The bridge supply's divider ([`supply`](crate::supply)): PC3, IN13 of
/// all three ADCs, read at boot by ADC1's regular group and then every
/// period by ADC3's injected group, after shunt 7 if any. On the Discovery
/// PC3 is the MEMS microphone's output: lift it (as PA4/PA5 for DAC
/// segments).
pub const BRIDGE_SUPPLY_SENSE: Input = Input {
    pin: Pin::new(b'C', 3),
    adc: 3,
    channel: 13,
};

/// Each segment's H-bridge legs (A, B), as `BOARD.md`'s table and the
/// board's `init` wire them (TIM1, TIM8, TIM2, TIM4 channel pairs).
pub const BRIDGE_LEGS: [(Pin, Pin); 8] = [
    (Pin::new(b'E', 9), Pin::new(b'E', 11)),
    (Pin::new(b'E', 13), Pin::new(b'E', 14)),
    (Pin::new(b'C', 6), Pin::new(b'C', 7)),
    (Pin::new(b'C', 8), Pin::new(b'C', 9)),
    (Pin::new(b'A', 15), Pin::new(b'B', 3)),
    (Pin::new(b'B', 10), Pin::new(b'B', 11)),
    (Pin::new(b'D', 12), Pin::new(b'D', 13)),
    (Pin::new(b'D', 14), Pin::new(b'D', 15)),
];

/// DAC1 and DAC2's outputs, for the segments that use them.
pub const DAC_OUTPUTS: [Pin; 2] = [Pin::new(b'A', 4), Pin::new(b'A', 5)];

/// The camera's sync LED ([`sync`](crate::sync)): PE7, a push-pull output
/// (RM0090 §8.3: MODER output, OTYPER push-pull) through a resistor to an
/// LED in the camera's view.
pub const SYNC_LED: Pin = Pin::new(b'E', 7);

/// The bridges' keep-alive ([`keepalive`](crate::keepalive)): PE10, a
/// push-pull output into the monostable that holds every DRV8833's nSLEEP
/// (firmware/BOARD.md, "Lock-up"). A header pin on the Discovery (check
/// its user manual's pin table, UM1472, before wiring one).
pub const KEEPALIVE: Pin = Pin::new(b'E', 10);

/// Whether `pin` is none of the drive's and sensors' pins: no bridge leg,
/// DAC output, analogue input of `map` or the supply's sense.
pub const fn is_free(pin: Pin, map: &[Input]) -> bool {
    let mut i = 0;
    while i < BRIDGE_LEGS.len() {
        let (a, b) = BRIDGE_LEGS[i];
        if a.is(pin.port, pin.number) || b.is(pin.port, pin.number) {
            return false;
        }
        i += 1;
    }
    let mut i = 0;
    while i < DAC_OUTPUTS.len() {
        if DAC_OUTPUTS[i].is(pin.port, pin.number) {
            return false;
        }
        i += 1;
    }
    let mut i = 0;
    while i < map.len() {
        if map[i].pin.is(pin.port, pin.number) {
            return false;
        }
        i += 1;
    }
    !BRIDGE_SUPPLY_SENSE.pin.is(pin.port, pin.number)
}

/// The sync LED is on a pin nothing else uses: checked at compile time.
pub const SYNC_LED_IS_FREE: bool = is_free(SYNC_LED, &MAP);
const _: () = assert!(
    SYNC_LED_IS_FREE,
    "the sync LED's pin is used by the drive or a sensor"
);

/// The keep-alive is on a pin nothing else uses, the sync LED's neither.
const _: () = assert!(
    is_free(KEEPALIVE, &MAP) && !KEEPALIVE.is(SYNC_LED.port, SYNC_LED.number),
    "the keep-alive's pin is used by the drive, a sensor or the sync LED"
);

/// The ADC whose injected group reads segment `i`'s shunt: at most four
/// conversions a group, the load cell first in ADC1's.
pub const fn adc_of_segment(i: usize) -> u8 {
    match i {
        0..=2 => 1,
        3..=6 => 2,
        _ => 3,
    }
}

/// Whether the datasheet puts `input`'s pin on `input`'s ADC at its channel.
pub const fn on_datasheet(input: Input) -> bool {
    let mut k = 0;
    while k < DATASHEET_LQFP100.len() {
        let (pin, adcs, channel) = DATASHEET_LQFP100[k];
        if pin.is(input.pin.port, input.pin.number) {
            let reaches = input.adc >= 1 && input.adc <= 3 && adcs & (1 << (input.adc - 1)) != 0;
            return reaches && channel == input.channel;
        }
        k += 1;
    }
    false
}

/// Whether every input of `map` (the load cell first, then the shunts) is
/// on the datasheet, no pin is wired twice, and each shunt is on the ADC
/// whose group reads it.
pub const fn is_wired(map: &[Input]) -> bool {
    let mut i = 0;
    while i < map.len() {
        if !on_datasheet(map[i]) {
            return false;
        }
        if i > 0 && map[i].adc != adc_of_segment(i - 1) {
            return false;
        }
        let mut j = 0;
        while j < i {
            if map[j].pin.is(map[i].pin.port, map[i].pin.number) {
                return false;
            }
            j += 1;
        }
        i += 1;
    }
    true
}

const MAP: [Input; 9] = {
    let mut map = [LOAD_CELL; 9];
    let mut i = 0;
    while i < 8 {
        map[i + 1] = SHUNTS[i];
        i += 1;
    }
    map
};

/// The board's map ([`LOAD_CELL`], [`SHUNTS`]) passes [`is_wired`], and the
/// supply's sense pin is on the datasheet and on no other input; a build
/// fails otherwise.
pub const MAP_IS_WIRED: bool = is_wired(&MAP) && sense_is_wired(BRIDGE_SUPPLY_SENSE, &MAP);

/// Whether `sense` is on the datasheet and shares no pin with `map`.
pub const fn sense_is_wired(sense: Input, map: &[Input]) -> bool {
    if !on_datasheet(sense) {
        return false;
    }
    let mut i = 0;
    while i < map.len() {
        if map[i].pin.is(sense.pin.port, sense.pin.number) {
            return false;
        }
        i += 1;
    }
    true
}

const _: () = assert!(
    MAP_IS_WIRED,
    "an analogue input is not where the datasheet puts it"
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_board_map_is_on_the_datasheet() {
        assert!(is_wired(&MAP));
        for (i, s) in SHUNTS.iter().enumerate() {
            assert!(on_datasheet(*s), "segment {i}: {s:?}");
            assert_eq!(s.adc, adc_of_segment(i), "segment {i}");
        }
    }

    #[test]
    fn a_pin_off_its_adc_a_wrong_channel_or_a_pin_twice_is_refused() {
        let mut map = MAP;
        // The old map: segment 7's shunt on PB1 for ADC3 (PB1 is ADC12_IN9).
        map[8] = Input {
            pin: Pin::new(b'B', 1),
            adc: 3,
            channel: 9,
        };
        assert!(!is_wired(&map));
        let mut map = MAP;
        map[1].channel = 3;
        assert!(!is_wired(&map), "PA2 is IN2");
        let mut map = MAP;
        map[2] = map[1];
        assert!(!is_wired(&map), "PA2 twice");
        let mut map = MAP;
        map[4].adc = 1;
        assert!(!is_wired(&map), "segment 3 belongs to ADC2's group");
        // The supply's sense pin on a shunt's, or off its channel.
        assert!(!sense_is_wired(
            Input {
                pin: Pin::new(b'C', 2),
                adc: 1,
                channel: 12
            },
            &MAP
        ));
        assert!(!sense_is_wired(
            Input {
                channel: 12,
                ..BRIDGE_SUPPLY_SENSE
            },
            &MAP
        ));
        assert!(sense_is_wired(BRIDGE_SUPPLY_SENSE, &MAP));
        // Port F is not on the LQFP100: ADC3_IN9 on PF3 is not there.
        assert!(!on_datasheet(Input {
            pin: Pin::new(b'F', 3),
            adc: 3,
            channel: 9
        }));
    }

    #[test]
    fn the_sync_led_is_on_a_free_pin_and_a_used_one_is_refused() {
        assert!(is_free(SYNC_LED, &MAP));
        // A bridge leg, a DAC output, a shunt, the supply's sense.
        for used in [
            Pin::new(b'E', 9),
            Pin::new(b'B', 3),
            Pin::new(b'D', 15),
            Pin::new(b'A', 5),
            Pin::new(b'C', 2),
            Pin::new(b'C', 3),
        ] {
            assert!(!is_free(used, &MAP), "{used:?}");
        }
        // No two legs share a pin.
        for (i, (a, b)) in BRIDGE_LEGS.iter().enumerate() {
            assert_ne!(a, b);
            for (c, d) in &BRIDGE_LEGS[i + 1..] {
                assert!(![c, d].contains(&a) && ![c, d].contains(&b));
            }
        }
    }

    #[test]
    fn the_table_is_the_datasheet_pattern() {
        // IN0..IN15 on PA0..PA7, PB0, PB1, PC0..PC5 in order; ADC3 only on
        // PA0..PA3 and PC0..PC3.
        for (k, (pin, adcs, channel)) in DATASHEET_LQFP100.iter().enumerate() {
            assert_eq!(usize::from(*channel), k);
            let adc3 = pin.number <= 3 && matches!(pin.port, b'A' | b'C');
            assert_eq!(*adcs, if adc3 { 0b111 } else { 0b011 }, "{pin:?}");
        }
    }
}
