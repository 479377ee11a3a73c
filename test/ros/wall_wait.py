"""What the rostest scripts share: waiting on the wall clock (never on simulated time, which a
paused node stops) for a condition, with the reason in the failure."""
import time


def wait_for(predicate, timeout, what, poll=0.05):
    end = time.time() + timeout
    while time.time() < end:
        if predicate():
            return
        time.sleep(poll)
    raise AssertionError("timed out after %g s waiting for %s" % (timeout, what))
