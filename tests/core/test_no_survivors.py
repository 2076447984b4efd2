"""The suite's guard against processes a test leaves behind (conftest.leaves_no_process): an
orphan that a test started keeps the test's tag in its environment and is found; one started
without the tag (another test's, a wider fixture's) is not."""
import os
import subprocess
import time

from conftest import PROCESS_TAG, tagged_survivors


def test_an_orphan_keeps_the_tests_tag_and_is_found_until_it_ends():
    since = time.time() - 1.0
    tag = os.environ[PROCESS_TAG]  # this test's own, set by the autouse fixture
    orphan = subprocess.Popen(["sleep", "30"], start_new_session=True)  # its own session, as a daemon's job
    untagged = subprocess.Popen(["sleep", "30"], env={k: v for k, v in os.environ.items() if k != PROCESS_TAG})
    try:
        found = {p.pid for p in tagged_survivors(tag, since)}
        assert orphan.pid in found and untagged.pid not in found
    finally:
        for proc in (orphan, untagged):
            proc.kill()
            proc.wait()
    assert not tagged_survivors(tag, since)  # killed and reaped: nothing of this test runs
