//! What the decoder does to a video's pictures before the pose model sees them: HDR video
//! (phones record it by default: iPhones HLG, many Android phones PQ) converted to the standard
//! range the pose models were trained on, and interlaced video (camcorders' 1080i) deinterlaced.
//!
//! Decoded as if it were standard video, an HLG or PQ frame comes out washed out and dark (on
//! the sample made HLG, a mean difference of 43 grey levels from the original; the pose model
//! then moved 4 of 12 events). zscale converts the transfer, primaries and matrix to BT.709,
//! clipping what lies above the standard range's white, as a standard camera would. An
//! interlaced frame holds two fields 1/50 or 1/60 s apart: a moving leg is drawn twice, combed.

/// The ffmpeg filter that turns frames with this transfer (ffprobe's `color_transfer`) into
/// standard-range BT.709, or `None` when they already are.
pub(crate) fn to_standard_range(transfer: &str) -> Option<&'static str> {
    match transfer {
        // HLG is relative to the display: its own nominal peak maps to white.
        "arib-std-b67" => Some("zscale=t=bt709:m=bt709:p=bt709:r=tv"),
        // PQ is absolute: its reference white is 203 cd/m2 (ITU-R BT.2408).
        "smpte2084" => Some("zscale=t=bt709:m=bt709:p=bt709:r=tv:npl=203"),
        _ => None,
    }
}

/// What the user is told about an HDR video, when it is one.
pub(crate) fn warning(transfer: &str) -> Option<String> {
    let name = match transfer {
        "arib-std-b67" => "HLG",
        "smpte2084" => "PQ (HDR10)",
        _ => return None,
    };
    Some(format!(
        "the video is HDR ({name}): its frames were converted to standard range (BT.709) for the pose model; highlights above white are clipped"
    ))
}

/// The ffmpeg filter that deinterlaces frames of this field order (ffprobe's `field_order`),
/// or `None` for progressive video: bwdif, one frame out per frame in (the frame rate and the
/// frame numbers stay), only on frames the decoder marks interlaced.
pub(crate) fn deinterlace(field_order: &str) -> Option<&'static str> {
    matches!(field_order, "tt" | "bb" | "tb" | "bt")
        .then_some("bwdif=mode=send_frame:parity=auto:deint=interlaced")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_hdr_transfers_are_converted() {
        assert!(to_standard_range("arib-std-b67").is_some());
        assert!(to_standard_range("smpte2084").unwrap().contains("npl=203"));
        for sdr in ["bt709", "smpte170m", "unknown", ""] {
            assert!(
                to_standard_range(sdr).is_none() && warning(sdr).is_none(),
                "{sdr}"
            );
        }
        assert!(warning("arib-std-b67").unwrap().contains("HLG"));
    }

    #[test]
    fn only_interlaced_field_orders_are_deinterlaced() {
        for order in ["tt", "bb", "tb", "bt"] {
            assert!(deinterlace(order).is_some(), "{order}");
        }
        for order in ["progressive", "unknown", ""] {
            assert!(deinterlace(order).is_none(), "{order}");
        }
    }
}
