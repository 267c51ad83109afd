"""An extra that is not installed is named, with the command that installs it."""

from __future__ import annotations

import pytest

from manifoundation.sdk import ManiError, MissingExtra
from manifoundation.sdk.extras import require


def test_a_missing_extra_names_itself() -> None:
    with pytest.raises(MissingExtra) as caught:
        require("no_such_package_for_the_view.graph_objects", "view", "result_figure")
    assert caught.value.extra == "view"
    assert "pip install 'manifoundation-client[view]'" in str(caught.value) and "result_figure" in str(caught.value)
    assert isinstance(caught.value, ImportError) and isinstance(caught.value, ManiError)


def test_an_installed_extra_is_imported_and_other_import_errors_stay_themselves() -> None:
    assert require("msgpack", "none", "test").packb(1) == b"\x01"
    with pytest.raises(ModuleNotFoundError) as caught:  # a broken install is not a missing extra
        require("msgpack.no_such_module", "none", "test")
    assert not isinstance(caught.value, MissingExtra)
