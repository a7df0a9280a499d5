"""An interruption whose traceback holds a frame without a line number (CPython 3.11 gives one when
a signal lands on an instruction that has none: seen once in CI, a SIGTERM during a Ray-dispatched
suite) crashed pytest's own report of the interruption ("unsupported operand type(s) for -:
'NoneType' and 'int'"), so the run ended with status 1, not 2 (interrupted), and without its
summary. The plugin numbers such frames before pytest formats the interruption."""
import pytest

LINELESS = '''
import types


def test_interrupted():
    def inner():
        raise ValueError("where the signal landed")
    try:
        inner()
    except ValueError as exc:
        frame = exc.__traceback__.tb_next.tb_frame
    lineless = types.TracebackType(None, frame, 10 ** 6, -1)     # an instruction with no line
    assert lineless.tb_lineno is None
    raise KeyboardInterrupt().with_traceback(lineless)
'''


def test_an_interruption_with_a_frame_without_a_line_number_ends_as_interrupted(pytester: pytest.Pytester):
    pytester.makepyfile(test_lineless=LINELESS)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")
    assert result.ret == pytest.ExitCode.INTERRUPTED, result.stdout.str()[-2000:]
    result.stdout.fnmatch_lines(["*KeyboardInterrupt*"])
    assert "NoneType" not in result.stdout.str() + result.stderr.str()
