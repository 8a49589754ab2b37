"""What the command line reads as a model file, and what it says when the paper's flags meet one.

A model file is recognised by its content (:func:`lyapcheck.models.language.modelfile.is_model_file`), so
``lyapcheck certify FILE`` and ``lyapcheck simulate FILE`` take one where the paper's gain or
scenario file would stand; ``--model FILE`` keeps working. On a model's path every message speaks
of the model: ``--set mu 1`` says ``use --set mu=1``, and a flag of the paper's loop names itself
as the paper's and says what to use instead.
"""

from __future__ import annotations

import contextlib
from typing import Iterator, Mapping, Sequence

from lyapcheck.errors import InvalidParameter, ModelFileError

#: what to do instead of a paper flag, on a model's path (the gain flags share the default)
PAPER_FLAG_HINTS: Mapping[str, str] = {
    "--worst-case": "for a model file, the worst-case disturbance search is `lyapcheck simulate FILE --worst-case`",
    "--linear-views": "for a model file, the linearization class gives the Jacobian and its exact verdict",
    "--dynamics": "it picks the paper's derived or printed equations; a model file states its own",
    "--preset": "the presets are the paper's Section 5 simulations; a model file states its own loop",
}
GAIN_FLAG_HINT = "a model file carries its own parameters: use --set NAME=VALUE"


def split_model_argument(positional: str | None, model_file: str | None) -> tuple[str | None, str | None]:
    """``(model_file, positional)``: a positional file that is a model file becomes the model."""
    from lyapcheck.models.language.modelfile import is_model_file

    if positional is not None and is_model_file(positional):
        if model_file is not None:
            raise InvalidParameter("model", "given once (FILE or --model FILE, not both)", positional)
        return positional, None
    return model_file, positional


def check_model_flags(source: str, positional: str | None, settings: Sequence[str],
                      paper_flags: Mapping[str, bool]) -> None:
    """Refuse, in the model's words and naming the model file ``source``, what does not belong with
    it: a ``--set`` whose value was given as a separate word (it then stands as the positional
    argument), a second input file, and the paper's flags (``paper_flags``: flag -> given)."""
    bare = [s for s in settings if "=" not in s]
    if bare:
        value = positional if positional is not None else "VALUE"
        words = f"--set {bare[0]}" + (f" {positional}" if positional is not None else "")
        raise ModelFileError(source, "set", f"must be NAME=VALUE in one word: use --set {bare[0]}={value} "
                                            f"(got '{words}')")
    if positional is not None:
        raise ModelFileError(source, "FILE", f"the model file is the only input file; '{positional}' has no use "
                                             "with it")
    for flag, given in paper_flags.items():
        if given:
            hint = PAPER_FLAG_HINTS.get(flag, GAIN_FLAG_HINT)
            raise ModelFileError(source, flag, f"is a flag of the paper's loop, left out with a model file ({hint})")


@contextlib.contextmanager
def flag_names() -> Iterator[None]:
    """The API's errors about a model's arguments re-raised in the command line's words:
    ``settings['mu']`` as ``--set mu``, ``candidate`` as ``--candidate``, ``box['mu']`` as ``--box mu``."""
    try:
        yield
    except ModelFileError as exc:
        message = str(exc).removeprefix(f"{exc.source}: {exc.key}: ")
        key = exc.key
        for argument, flag in (("settings", "--set"), ("candidate", "--candidate"), ("box", "--box")):
            if key == argument or key.startswith(argument + "['") and key.endswith("']"):
                name = key[len(argument) + 2:-2] if key != argument else ""
                raise ModelFileError(exc.source, f"{flag} {name}".strip() if name or flag != "--set" else "set",
                                     message) from None
        raise


__all__ = ["split_model_argument", "check_model_flags", "flag_names", "PAPER_FLAG_HINTS"]
