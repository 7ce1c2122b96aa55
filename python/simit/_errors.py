"""The exceptions the simit module raises; simit.Error is the base of all of them."""


class Error(Exception):
    """A Simit error: misuse of the API, a scene or mesh problem, or one of the below."""


class Diagnostic:
    """One compile diagnostic: where (1-based line and column) and what."""

    def __init__(self, line, column, category, message, rendered=""):
        self.line = line
        self.column = column
        self.category = category
        self.message = message
        self.rendered = rendered

    def __repr__(self):
        return f"Diagnostic(line={self.line}, column={self.column}, message={self.message!r})"


class CompileError(Error):
    """The program did not compile; .diagnostics lists every problem."""

    def __init__(self, message, diagnostics=()):
        super().__init__(message)
        self.diagnostics = list(diagnostics)


class BindError(Error):
    """A binding does not match the program; .problems has one line per problem."""

    def __init__(self, message, problems=()):
        super().__init__(message)
        self.problems = list(problems)


class RuntimeError(Error):  # noqa: A001 - the API's name for it, as in C++
    """The program stopped with a run-time error; the message names the .sim line and the
    element; .line is the line (0 when the error has none)."""

    def __init__(self, message, line=0):
        super().__init__(message)
        self.line = line


# Shown as simit.Error, simit.CompileError, ... in tracebacks: the names users import.
for _cls in (Error, Diagnostic, CompileError, BindError, RuntimeError):
    _cls.__module__ = "simit"
