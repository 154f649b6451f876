"""Renderer options declared once (`OptionSpec`): parsing, validation and help come from the spec."""

from __future__ import annotations

import math

import pytest

from volren.errors import VolrenError
from volren.renderers.base import OptionRule, OptionSpec, RendererBase, option_help_of, parse_options

SPECS = (
    OptionSpec("skip", True, "bool", "skip empty bricks"),
    OptionSpec("size", 256, "int", "table entries", low=16, high=4096),
    OptionSpec("seed", 0, "int", "random seed", low=0),
    OptionSpec("alpha", 0.999, "float", "opacity that stops a ray", low=0.0, high=1.0, low_exclusive=True),
    OptionSpec("tolerance", 1e-5, "float", "convergence tolerance", low=0.0, low_exclusive=True),
    OptionSpec("mode", "interleaved", "choice", "depth offsets", choices=("interleaved", "midpoint")),
    OptionSpec("label", "x", "str", "a label"),
    OptionSpec("oversampling", "auto", "float", "pixels per pixel", low=0.25, high=8.0, words=("auto",)),
    OptionSpec("stride", 1, "int", "ray spacing", rule=OptionRule(lambda v: 1 <= v <= 64 and v & (v - 1) == 0,
                                                                  "1, 2, 4, 8, 16, 32 or 64")),
)  # fmt: skip


def parse(**options):
    return parse_options("demo", SPECS, options)


def test_defaults_fill_in_options_not_given():
    assert parse() == {"skip": True, "size": 256, "seed": 0, "alpha": 0.999, "tolerance": 1e-5, "mode": "interleaved",
                       "label": "x", "oversampling": "auto", "stride": 1}  # fmt: skip


def test_given_values_are_kept_and_ints_become_floats_for_float_options():
    opts = parse(skip=False, size=16, alpha=1, oversampling=8, mode="midpoint", stride=64, seed=2**70)
    assert (
        opts["skip"] is False and opts["size"] == 16 and opts["mode"] == "midpoint" and opts["stride"] == 64
    )
    assert opts["alpha"] == 1.0 and type(opts["alpha"]) is float
    assert opts["oversampling"] == 8.0 and type(opts["oversampling"]) is float
    assert opts["seed"] == 2**70


@pytest.mark.parametrize(
    "options, message",
    [
        ({"skip": 1}, "renderer demo: option skip must be true or false, got 1"),
        ({"skip": "yes"}, "option skip must be true or false, got 'yes'"),
        ({"size": True}, "option size must be an integer in 16..4096, got True"),
        ({"size": 256.0}, "option size must be an integer in 16..4096, got 256.0"),
        ({"size": 8}, "option size must be an integer in 16..4096, got 8"),
        ({"size": 10**400}, "option size must be an integer in 16..4096, got an integer of about 401 digits"),
        ({"seed": -1}, "option seed must be an integer >= 0, got -1"),
        ({"alpha": 0}, "option alpha must be a number in (0, 1], got 0"),
        ({"alpha": math.nan}, "option alpha must be a number in (0, 1], got nan"),
        ({"alpha": False}, "option alpha must be a number in (0, 1], got False"),
        ({"alpha": "0.5"}, "option alpha must be a number in (0, 1], got '0.5'"),
        ({"tolerance": math.inf}, "option tolerance must be a number > 0, got inf"),
        ({"tolerance": math.nan}, "option tolerance must be a number > 0, got nan"),
        ({"tolerance": 10**400}, "option tolerance must be a number > 0, got an integer of about 401 digits"),
        ({"mode": "random"}, "option mode must be one of 'interleaved', 'midpoint', got 'random'"),
        ({"mode": ["midpoint"]}, "option mode must be one of 'interleaved', 'midpoint', got ['midpoint']"),
        ({"label": 3}, "option label must be a string, got 3"),
        ({"oversampling": "fine"}, "option oversampling must be 'auto' or a number in [0.25, 8], got 'fine'"),
        ({"oversampling": 0.1}, "option oversampling must be 'auto' or a number in [0.25, 8], got 0.1"),
        ({"stride": 3}, "option stride must be 1, 2, 4, 8, 16, 32 or 64, got 3"),
        ({"stride": 128}, "option stride must be 1, 2, 4, 8, 16, 32 or 64, got 128"),
        ({"stride": 2.0}, "option stride must be 1, 2, 4, 8, 16, 32 or 64, got 2.0"),
        ({"mode": "y" * 500}, "option mode must be one of 'interleaved', 'midpoint', got 'yyyy"),
    ],
)
def test_bad_values_are_one_line_errors_naming_the_option_and_what_it_accepts(options, message):
    with pytest.raises(VolrenError) as info:
        parse(**options)
    text = str(info.value)
    assert message in text and "\n" not in text and len(text) < 200


def test_unknown_options_keep_the_one_line_wording_with_the_valid_names():
    with pytest.raises(VolrenError) as info:
        parse(colour=1)
    assert str(info.value) == ("renderer demo has no option(s) ['colour']; valid: alpha, label, mode, oversampling, "
                               "seed, size, skip, stride, tolerance")  # fmt: skip


def test_a_value_equal_to_a_choice_of_another_type_is_refused():
    spec = OptionSpec("factor", 1, "choice", "downsampling", choices=(1, 2, 4, 8))
    assert spec.parse(4, "demo") == 4
    for bad in (True, 2.0, "2"):
        with pytest.raises(VolrenError, match="option factor must be one of 1, 2, 4, 8"):
            spec.parse(bad, "demo")


def test_the_help_line_is_derived_from_the_spec():
    help_ = option_help_of(SPECS)
    assert help_["size"] == "table entries [an integer in 16..4096; default 256]"
    assert help_["skip"] == "skip empty bricks [true or false; default true]"
    assert help_["oversampling"] == "pixels per pixel ['auto' or a number in [0.25, 8]; default auto]"
    assert help_["alpha"] == "opacity that stops a ray [a number in (0, 1]; default 0.999]"
    assert help_["stride"] == "ray spacing [1, 2, 4, 8, 16, 32 or 64; default 1]"
    assert (
        OptionSpec("mapper", None, "choice", "the mapper", choices=("a", "b")).describe()
        == "the mapper [one of 'a', 'b']"
    )


@pytest.mark.parametrize(
    "make, message",
    [
        (
            lambda: OptionSpec("size", 8, "int", "entries", low=16),
            "option size: the default 8 is not an integer >= 16",
        ),
        (lambda: OptionSpec("mode", "a", "enum", "a mode"), "kind must be one of"),
        (lambda: OptionSpec("mode", "a", "choice", "a mode"), "choices go with kind 'choice'"),
        (lambda: OptionSpec("size", 8, "int", "entries", low=0, low_exclusive=True), "exclusive low bound"),
    ],
)
def test_a_bad_spec_is_refused_where_it_is_declared(make, message):
    with pytest.raises(VolrenError, match=message):
        make()


def test_a_renderer_class_setting_option_help_by_hand_is_refused():
    with pytest.raises(VolrenError, match="declare `options`"):
        type(
            "HandHelp", (RendererBase,), {"options": SPECS[:1], "option_help": {"skip": "skip empty bricks"}}
        )


# ------------------------------------------------------------------------ the conformance kit
def _options_check(renderer_class: type) -> list[str]:
    """The FAIL lines of the kit's options check on `renderer_class`."""
    from volren.testing import CHECKS, run_check

    check = next(c for c in CHECKS if c.name == "options")
    return run_check(check, renderer_class, quick=True).failures()


def test_the_kit_passes_options_declared_through_the_spec():
    from tests.renderers.protocol_renderer import PlainRenderer

    assert _options_check(PlainRenderer) == []


def test_the_kit_fails_options_parsed_outside_the_spec():
    from tests.renderers.protocol_renderer import PlainRenderer

    class OwnParsing(PlainRenderer):
        """Declares its option but reads settings.options itself, accepting anything."""

        def set_settings(self, settings):
            self._alpha = settings.options.get("alpha", 0.5)

    class Undeclared(PlainRenderer):
        options = None

    class HandWrittenHelp(PlainRenderer):
        option_help = {"alpha": "the opacity drawn"}

    assert any(
        "bad values accepted (alpha, volren_kit_no_such_option)" in line
        for line in _options_check(OwnParsing)
    )
    assert any("not declared as a tuple of OptionSpec" in line for line in _options_check(Undeclared))
    assert any("not the one derived from `options`" in line for line in _options_check(HandWrittenHelp))
