"""render(derivatives=[...]) (docs/python.md §2, docs/derivatives.md): the argument refused before any work
with a message naming it, and the derivative images equal to the command line's `--derivative` images."""
import pytest

import dartspp

BAD = [
    ("/media/0/sigma_s", r"^derivatives: expected a list of JSON Pointers, not a single str"),
    (b"/media/0/sigma_s", r"^derivatives: expected a list of JSON Pointers, not a single bytes"),
    (3, r"^derivatives: expected a list of JSON Pointers \(str\), not int"),
    ({"/media/0/sigma_s": 1}, r"^derivatives: expected a list of JSON Pointers \(str\), not dict"),
    (["/media/0/sigma_s", 7], r"^derivatives\[1\]: expected a JSON Pointer \(str\), not int"),
    (["media/0/sigma_s"], r"^derivatives\[0\]: 'media/0/sigma_s' is not a JSON Pointer to a parameter"),
    ([""], r"^derivatives\[0\]: '' is not a JSON Pointer to a parameter"),
    (["/media/0/sigma_s"] * 9, r"^derivatives: 9 pointers given; a render differentiates at most 8 parameters"),
    (["/media/0/sigma_\0s"], r"^derivatives\[0\]: .*no NUL character"),
    (["/" + "m" * 255], r"^derivatives\[0\]: .*at most 255 bytes"),
]


@pytest.mark.parametrize("value,message", BAD, ids=["str", "bytes", "int", "dict", "item-int", "no-slash", "empty",
                                                     "nine", "nul", "long"])
def test_derivatives_argument_refused(fogbox, value, message):
    """A bad derivatives argument raises SceneError naming it (and the item), before any work: the render's
    progress callback is never called."""
    calls = []
    with pytest.raises(dartspp.SceneError, match=message):
        dartspp.render(fogbox, spp=1, derivatives=value, progress=lambda *a: calls.append(a))
    assert calls == []


def test_no_derivatives(fogbox):
    """Without derivatives the result says so: None for the images, [] for the pointers."""
    r = dartspp.render(fogbox, spp=1, seed=3)
    assert r.derivatives is None and r.derivative_frames is None and r.derivative_pointers == []
