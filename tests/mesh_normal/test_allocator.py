"""The allocator settings: they take effect on glibc, keep freed memory in the process for the
command line's one job, and give it back when asked."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from mesh_normal import allocator, cli

GLIBC = allocator.libc("mallopt") is not None


def run(code: str) -> str:
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, check=True
    )
    return done.stdout


@pytest.mark.skipif(not GLIBC, reason="the settings are glibc's")
def test_freed_memory_is_kept_then_given_back() -> None:
    """After a freed 256 MB block, the process still holds it (kept for the next), and
    ``give_back`` returns it; without ``keep_freed`` glibc unmaps it at once."""
    code = """
        import numpy as np
        from mesh_normal import allocator

        def resident():
            with open("/proc/self/statm") as statm:
                return int(statm.read().split()[1]) * 4096 >> 20

        if KEEP:
            assert allocator.keep_freed()
        block = np.ones(2**28, dtype=np.uint8)
        held = resident()
        del block
        kept = resident()
        allocator.give_back()
        print(held, kept, resident())
    """
    held, kept, after = map(int, run("KEEP = True\n" + textwrap.dedent(code)).split())
    assert kept > held - 16 and after < held - 200
    held, kept, after = map(int, run("KEEP = False\n" + textwrap.dedent(code)).split())
    assert kept < held - 200


def test_the_command_line_tunes_the_allocator_only_in_its_own_process(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    enabled: list[bool] = []
    monkeypatch.setattr(allocator, "enable_jobs", lambda: enabled.append(True))
    monkeypatch.setattr(sys, "argv", ["mesh-normal", "normals", "--help"])
    with pytest.raises(SystemExit):
        cli.main()
    assert enabled == []  # --help ends before any work
    monkeypatch.setattr(sys, "argv", ["mesh-normal", "analyze", "/nonexistent.obj"])
    cli.main()
    assert enabled == [True]
    cli.main(["analyze", "/nonexistent.obj"])  # called in a host's process: left alone
    assert enabled == [True]


@pytest.mark.skipif(not GLIBC, reason="the settings are glibc's")
def test_prefault_brings_in_the_memory_the_next_arrays_use() -> None:
    """The prefaulted block is resident once the thread ends, and the next array is cut from
    it (the process does not grow again); without ``keep_freed`` nothing is done."""
    code = """
        import numpy as np
        from mesh_normal import allocator

        def resident():
            with open("/proc/self/statm") as statm:
                return int(statm.read().split()[1]) * 4096 >> 20

        assert allocator.prefault(2**28) is None  # the heap would not keep it
        assert allocator.keep_freed()
        before = resident()
        thread = allocator.prefault(2**28)
        thread.join()
        faulted = resident()
        block = np.ones(2**27, dtype=np.uint8)
        print(before, faulted, resident(), int(block.sum()) >> 20)
    """
    before, faulted, after, total = map(int, run(code).split())
    assert faulted > before + 200  # 256 MB in
    assert after < faulted + 16  # the 128 MB array took no new memory
    assert total == 128


def test_the_command_line_keeps_and_prefaults_for_large_binary_stl_only(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from mesh_normal.files import read

    asked: list[int] = []
    monkeypatch.setattr(allocator, "start_job", asked.append)
    obj = tmp_path / "one.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    stl = tmp_path / "one.stl"
    normal, corners = b"\0" * 12, np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "<f4").tobytes()
    stl.write_bytes(b"\0" * 80 + (1).to_bytes(4, "little") + normal + corners + b"\0\0")
    assert cli.main(["analyze", str(stl)]) == 0
    assert asked == []  # a small file: nothing to gain
    monkeypatch.setattr(read, "MAPPED_BYTES", 10)
    assert cli.main(["analyze", str(obj)]) == 0
    assert asked == []  # a text format: more memory, no time gained
    assert cli.main(["analyze", str(stl)]) == 0
    assert asked == [allocator.ARRAYS_PER_STL_BYTE * stl.stat().st_size]


@pytest.mark.skipif(not GLIBC, reason="the settings are glibc's")
def test_prefault_past_one_block_keeps_every_block() -> None:
    """More than the largest block: several, kept apart, all faulted in and all kept (none
    merges into a free top that the allocator would return)."""
    code = """
        import numpy as np
        from mesh_normal import allocator

        def resident():
            with open("/proc/self/statm") as statm:
                return int(statm.read().split()[1]) * 4096 >> 20

        allocator.PREFAULT_LIMIT = 2**26
        assert allocator.keep_freed()
        before = resident()
        allocator.prefault(5 * 2**26).join()
        faulted = resident()
        arrays = [np.ones(50 * 2**20, dtype=np.uint8) for _ in range(4)]
        print(before, faulted, resident())
    """
    before, faulted, after = map(int, run(code).split())
    assert faulted > before + 5 * 64 - 8
    assert after < faulted + 16  # 200 MB of arrays in the blocks
