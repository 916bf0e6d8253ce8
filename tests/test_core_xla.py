"""`one_thread_options`: the option that skips XLA:CPU's loop split keeps the passes XLA_FLAGS disables."""

from __future__ import annotations

import pytest

from jaxplan.core.xla import PARALLEL_TASK_PASS, one_thread_options


@pytest.mark.parametrize("flags, passes", [
    ("", [PARALLEL_TASK_PASS]),
    ("--xla_force_host_platform_device_count=2", [PARALLEL_TASK_PASS]),
    ("--xla_disable_hlo_passes=rematerialization", ["rematerialization", PARALLEL_TASK_PASS]),
    ("--xla_disable_hlo_passes=a,b --xla_cpu_enable_fast_math=false", ["a", "b", PARALLEL_TASK_PASS]),
    ("--xla_disable_hlo_passes=a --xla_disable_hlo_passes=b", ["b", PARALLEL_TASK_PASS]),  # the last flag wins
    (f"--xla_disable_hlo_passes={PARALLEL_TASK_PASS},c", [PARALLEL_TASK_PASS, "c"]),
])
def test_the_option_adds_the_parallel_task_pass_to_the_flags_list(monkeypatch, flags, passes):
    monkeypatch.setenv("XLA_FLAGS", flags)
    assert one_thread_options() == {"xla_disable_hlo_passes": ",".join(passes)}


def test_without_xla_flags(monkeypatch):
    monkeypatch.delenv("XLA_FLAGS", raising=False)
    assert one_thread_options() == {"xla_disable_hlo_passes": PARALLEL_TASK_PASS}
