//! The measured columns a recording may carry besides time and voltages.

/// A measured column. Indices are 0-based; names are 1-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// `iK_A`: current into segment K, A.
    Current(usize),
    /// `tip_y_m`: tip displacement across the strip, m.
    TipY,
    /// `tip_x_m`: tip displacement along the strip, m.
    TipX,
    /// `force_N`: blocking force on the load cell, N.
    Force,
    /// `dotJ_y_m`: tracked dot J across the strip, m.
    DotY(usize),
    /// `dotJ_x_m`: tracked dot J along the strip, m.
    DotX(usize),
}

impl Channel {
    /// The column's header name.
    pub fn name(&self) -> String {
        match self {
            Channel::Current(k) => format!("i{}_A", k + 1),
            Channel::TipY => "tip_y_m".to_string(),
            Channel::TipX => "tip_x_m".to_string(),
            Channel::Force => "force_N".to_string(),
            Channel::DotY(j) => format!("dot{}_y_m", j + 1),
            Channel::DotX(j) => format!("dot{}_x_m", j + 1),
        }
    }

    /// The channel a header name denotes, if any (indices unchecked here).
    pub fn parse(name: &str) -> Option<Channel> {
        let index = |digits: &str| -> Option<usize> {
            // Canonical decimal only: "01" or "+1" would not round-trip.
            if digits.is_empty()
                || digits.starts_with('0')
                || !digits.bytes().all(|b| b.is_ascii_digit())
            {
                return None;
            }
            digits.parse::<usize>().ok().map(|n| n - 1)
        };
        match name {
            "tip_y_m" => Some(Channel::TipY),
            "tip_x_m" => Some(Channel::TipX),
            "force_N" => Some(Channel::Force),
            _ => {
                if let Some(k) = name.strip_prefix('i').and_then(|r| r.strip_suffix("_A")) {
                    index(k).map(Channel::Current)
                } else if let Some(j) = name
                    .strip_prefix("dot")
                    .and_then(|r| r.strip_suffix("_y_m"))
                {
                    index(j).map(Channel::DotY)
                } else if let Some(j) = name
                    .strip_prefix("dot")
                    .and_then(|r| r.strip_suffix("_x_m"))
                {
                    index(j).map(Channel::DotX)
                } else {
                    None
                }
            }
        }
    }

    /// Whether the camera measures it (free fixture only).
    pub fn is_camera(&self) -> bool {
        matches!(
            self,
            Channel::TipY | Channel::TipX | Channel::DotY(_) | Channel::DotX(_)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for ch in [
            Channel::Current(0),
            Channel::Current(7),
            Channel::TipY,
            Channel::TipX,
            Channel::Force,
            Channel::DotY(0),
            Channel::DotX(11),
        ] {
            assert_eq!(Channel::parse(&ch.name()), Some(ch));
        }
        for bad in [
            "i0_A", "i01_A", "i_A", "dotx_y_m", "force_n", "v1_V", "t_s", "i+1_A",
        ] {
            assert_eq!(Channel::parse(bad), None, "{bad}");
        }
    }
}
