"""A scheduler written from docs/wire-protocol.md ("Commands and replies") with the Python
participant, for `sensornet conform scheduler` (ConformScheduler.* in conform_test.cpp): once
the first episode is announced it asks for a re-plan with the info surrogate, then for the
run's status, each Command written again every 2 s until its reply, and leaves (also on
RUN_SHUTDOWN). --break makes
it break one rule on purpose:

  no-retry    writes each command once and waits for its reply in vain  -> retries
  launcher    writes in P/launcher, the launcher's partition            -> by-right
  reuse-id    gives the second command the first one's id               -> command-ids
  deaf        writes every command three times, 2 s apart, replies or not -> replies-read
  refused     asks for a surrogate that does not exist                  -> accepted
  stay        does not leave after its commands                         -> leaving
"""

import argparse
import sys
import time

import sensornet

RESEND_S = 2.0


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--run-id", required=True)
    parser.add_argument("--domain-id", type=int, required=True)
    parser.add_argument("--break", dest="broken", default="none",
                        choices=["none", "no-retry", "launcher", "reuse-id", "deaf", "refused",
                                 "stay"])
    args = parser.parse_args()
    p = sensornet.Participant(args.run_id, domain_id=args.domain_id)
    controls, replies = p.reader("EpisodeControl"), p.reader("CommandReply")
    commands = p.writer("Command", "launcher" if args.broken == "launcher" else "operator")

    deadline = time.monotonic() + 60
    while not any(c["command"] == "EPISODE_START" for c in controls.take()):
        if time.monotonic() > deadline:
            sys.exit("python_scheduler: no episode was announced within 60 s")
        time.sleep(0.02)

    asks = [{"kind": "COMMAND_REPLAN",
             "surrogate": "nonsense" if args.broken == "refused" else "info"},
            {"kind": "COMMAND_STATUS"}]
    first_id = None
    for ask in asks:
        command_id = time.time_ns()
        if args.broken == "reuse-id" and first_id is not None:
            command_id = first_id
        first_id = first_id or command_id
        command = dict(ask, run_id=args.run_id, command_id=command_id,
                       issuer="python_scheduler.py", issued_wall_time_ns=time.time_ns())
        reply, copies, written = None, 0, 0.0
        give_up = time.monotonic() + 20
        while time.monotonic() < give_up:
            resend_due = time.monotonic() - written >= RESEND_S
            wanted = copies < 3 if args.broken == "deaf" else reply is None
            if wanted and resend_due and (copies == 0 or args.broken != "no-retry"):
                commands.write(command)
                copies, written = copies + 1, time.monotonic()
            for r in replies.take():
                if r["command_id"] == command_id and r["run_id"] == args.run_id:
                    reply = reply or r
            if reply is not None and not wanted:
                break
            if args.broken == "no-retry" and time.monotonic() - written > 3:
                break
            if any(c["command"] == "RUN_SHUTDOWN" for c in controls.take()):
                print("the run shut down", flush=True)
                return
            time.sleep(0.01)
        print(f"command {command_id} ({ask['kind']}): {copies} copies, reply {reply}", flush=True)

    if args.broken == "stay":
        while True:
            time.sleep(1)
    p.close()


if __name__ == "__main__":
    main()

