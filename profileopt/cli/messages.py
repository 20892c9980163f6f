"""Library messages in the command line's words: parameter names become the flags that set them."""

from __future__ import annotations

import re

__all__ = ["API_FLAGS", "API_FLAGS_ASSIGNED", "flags_for_parameters", "printable"]

#: The library names its parameters in messages (``segment_length_m = 0 m: must be > 0``);
#: the command line says its flags instead. Names that are also plain words (model, band)
#: are replaced only where a message assigns them (``model = 'x'``); a quoted name is a
#: file's key (``key 'max_jerk_mps3'`` of a vehicle file) and stays as it is.
API_FLAGS = {"segment_length_m": "--segment-length", "roughness_window_m": "--roughness-window",
             "path_tolerance_m": "--path-tolerance", "v0_mps": "--v0",
             "vend_mps": "--vend", "n_stages": "--stages", "spacing_m": "--spacing", "corridor_m": "--corridor",
             "max_gap_m": "--max-gap", "track_crs": "--track-crs", "terrain_crs": "--terrain-crs",
             "track_index": "--track-index", "roughness_class": "--roughness-class",
             "sensor_range_m": "--sensor-range", "cycle_s": "--cycle", "sensor_noise_m": "--sensor-noise",
             "sensor_spacing_m": "--sensor-spacing", "unseen_descent": "--unseen-descent",
             "keep_contact": "--keep-contact", "force_margin": "--force-margin"}
#: max_jerk_mps3 is a vehicle file's key too: only ``max_jerk_mps3 = ...`` (or a message's
#: ``ri VALUE``, the form of an option and its argument) is the option.
API_FLAGS_ASSIGNED = {"model": "--model", "smoothing": "--smoothing", "method": "--method", "band": "--band",
                      "max_jerk_mps3": "--max-jerk", "ri": "--ri", "unseen": "--unseen"}
_FLAG_PATTERN = re.compile(r"(?<![\w'])(" + "|".join(API_FLAGS) + r")(?![\w'])")
_ASSIGNED_PATTERN = re.compile(r"(?<![\w.'-])(" + "|".join(API_FLAGS_ASSIGNED) + r")(?= = | VALUE\b)")
#: A keyword argument as Python writes it, ``(model='dynamic')``: the option and its value,
#: ``(--model dynamic)``.
_KEYWORD_PATTERN = re.compile(r"(?<![\w.'-])(" + "|".join(API_FLAGS_ASSIGNED) + r")='([^'\s]*)'")


def flags_for_parameters(message: str) -> str:
    """A library message with API parameter names replaced by the command's flags.

    Parameters
    ----------
    message : str
        An :class:`~profileopt.errors.InputError` message.

    Returns
    -------
    str
    """
    message = _FLAG_PATTERN.sub(lambda m: API_FLAGS[m.group(1)], message)
    message = _KEYWORD_PATTERN.sub(lambda m: f"{API_FLAGS_ASSIGNED[m.group(1)]} {m.group(2)}", message)
    return _ASSIGNED_PATTERN.sub(lambda m: API_FLAGS_ASSIGNED[m.group(1)], message)


def printable(text: str) -> str:
    """A file name as text any writer takes: bytes that are not UTF-8 (kept by Python as
    lone surrogates, which matplotlib's fonts refuse) shown as U+FFFD.

    Parameters
    ----------
    text : str
        A name from the command line or the file system.

    Returns
    -------
    str
    """
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "replace")
