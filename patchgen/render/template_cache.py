"""The sheet templates compiled once per installation, not once per run.

jinja2 compiles a template to Python each time a process first loads it: 30-40 ms a run for the
patch sheet's two. Its bytecode cache keeps the compiled code on disk, beside numba's kernels
(``$XDG_CACHE_HOME/patchgen/templates``, else ``~/.cache/patchgen/templates``), and takes it
only for the same template source (jinja2 checks a checksum of it), the same jinja2 and Python,
and here also the same environment settings: the compiled code depends on them and jinja2's own
key does not. A cache that cannot be made, read or written is no cache: the template is compiled
as before. The sheets are the same bytes either way.
"""

from __future__ import annotations

import os
import pickle

import jinja2


def bytecode_cache(folder: str | None = None) -> jinja2.BytecodeCache | None:
    """The cache for patchgen's templates, in ``folder`` (default: see the module docstring);
    None when the folder cannot be made."""
    if folder is None:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        folder = os.path.join(base, "patchgen", "templates")
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError:
        return None
    return _Cache(folder)


def _settings(env: jinja2.Environment) -> str:
    """What the compiled code depends on besides the source, jinja2 and Python (see the module docstring)."""
    return repr((jinja2.__version__, env.autoescape, env.trim_blocks, env.lstrip_blocks, env.keep_trailing_newline,
                 env.newline_sequence, env.block_start_string, env.block_end_string, env.variable_start_string,
                 env.variable_end_string, env.comment_start_string, env.comment_end_string,
                 env.line_statement_prefix, env.line_comment_prefix, env.optimized, sorted(env.extensions)))


class _Cache(jinja2.FileSystemBytecodeCache):
    """jinja2's file cache, keyed by the environment's settings as well; a file that cannot be read
    or written, or is not whole, is a miss."""

    def get_bucket(self, environment, name, filename, source):
        return super().get_bucket(environment, f"{name}|{_settings(environment)}", filename, source)

    def load_bytecode(self, bucket) -> None:
        try:
            super().load_bytecode(bucket)
        except (OSError, EOFError, ValueError, TypeError, pickle.UnpicklingError):
            bucket.reset()

    def dump_bytecode(self, bucket) -> None:
        try:
            super().dump_bytecode(bucket)
        except OSError:
            pass
