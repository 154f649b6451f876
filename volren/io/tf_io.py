"""Transfer-function files: DESIGN.md's JSON of either kind (1D or 2D; read and written) and
ParaView presets (read, as 1D)."""

from __future__ import annotations

from pathlib import Path

from volren.errors import VolrenError, file_error
from volren.io.json_text import read_json, write_json
from volren.io.paraview_presets import is_preset_data, preset_to_tf, select_preset
from volren.model.channels import ChannelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import (
    TransferFunction,
    TransferFunction2D,
    transfer_function_from_dict,
)


def tf_from_data(data: object, path: Path, name: str | None = None) -> TransferFunction:
    """A TF from parsed JSON: our format (a 1D or 2D TF by its "kind"), or ParaView preset(s)
    (`name` picks one)."""
    if is_preset_data(data):
        return preset_to_tf(select_preset(data, name, path), path)
    if name is not None:
        raise file_error(
            path, "holds a volren transfer function, not ParaView presets, so name= does not apply"
        )
    if isinstance(data, list):
        raise file_error(path, "a JSON list that is not a list of ParaView presets")
    try:
        return transfer_function_from_dict(data)  # type: ignore[arg-type]
    except VolrenError as exc:
        raise file_error(path, str(exc)) from None
    except (TypeError, ValueError, KeyError) as exc:
        raise file_error(path, f"not a valid transfer function: {exc}") from None


def load_transfer_function(path: str | Path, name: str | None = None) -> TransferFunction:
    """Read a TF file: DESIGN.md's JSON (TransferFunction1D or TransferFunction2D by its "kind"),
    or a ParaView preset file (the first preset, or `name`)."""
    path = Path(path)
    return tf_from_data(read_json(path), path, name)


def load_any_transfer_function(path: str | Path) -> TransferFunction | ChannelTransferFunction:
    """`load_transfer_function`, or a TF per channel (kind "channels", `ChannelTransferFunction`)."""
    path = Path(path)
    data = read_json(path)
    if isinstance(data, dict) and data.get("kind") == "channels":
        try:
            return ChannelTransferFunction.from_dict(data)
        except VolrenError as exc:
            raise file_error(path, str(exc)) from None
    return tf_from_data(data, path)


def save_transfer_function(tf: TransferFunction | ChannelTransferFunction, path: str | Path) -> None:
    """Write DESIGN.md's TF JSON (version 1, either kind, or a TF per channel), keeping keys this
    version does not know."""
    if not isinstance(tf, TransferFunction1D | TransferFunction2D | ChannelTransferFunction):
        raise VolrenError(
            f"{path}: expected a TransferFunction1D or TransferFunction2D to save, got {type(tf).__name__}"
        )
    write_json(tf.to_dict(), Path(path))
