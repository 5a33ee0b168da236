#!/usr/bin/env python3
"""Check `adam logs candump` with cantools: our DBC decodes the dumped frames to the logged commands.

Usage: python3 tests/python/check_candump.py ADAM_BINARY RUN.mcap

1. Makes (once) its own venv, `target/py-candump-venv` (or $ADAM_PY_VENV), with `cantools`,
   `mcap` and `zstandard` from PyPI, and re-runs itself there.
2. Writes the log's frames as a candump log with `ADAM logs candump RUN.mcap --out …`.
3. Parses that file with cantools' own candump-log parser and decodes every A1 command frame
   (ids 0x100 + m) with `drivers/a1_can.dbc`.
4. Reads the `/command` channel and the attached runtime config from the MCAP with the
   official `mcap` reader, maps motor ids to joints, and requires every decoded field
   (q_des, dq_des, kp, kd, tau_ff, mode) to equal the logged command within half its DBC
   factor (or the clamp of a saturated field). Exchange k sends the commands of tick k - 1,
   so the frames of the k-th exchange are checked against the `/command` message of tick k - 1.

Prints one summary line; exits non-zero on the first mismatch. Not run by CI (it installs from
PyPI); `tests/udp_link.rs` runs it when ADAM_PYTHON_CHECKS=1.
"""

import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
VENV = os.environ.get("ADAM_PY_VENV", os.path.join(ROOT, "target", "py-candump-venv"))
PY = os.path.join(VENV, "bin", "python")


def ensure_venv():
    if os.path.abspath(sys.prefix) == os.path.abspath(VENV):
        return
    if not os.path.exists(PY):
        subprocess.run([sys.executable, "-m", "venv", VENV], check=True)
        subprocess.run(
            [PY, "-m", "pip", "install", "-q", "cantools", "mcap", "zstandard"], check=True
        )
    os.execv(PY, [PY, os.path.abspath(__file__)] + sys.argv[1:])


def main(adam, log):
    import tomllib

    import cantools
    from cantools.logreader import Parser
    from mcap.reader import make_reader

    db = cantools.database.load_file(os.path.join(ROOT, "drivers", "a1_can.dbc"))
    with tempfile.TemporaryDirectory() as tmp:
        dump = os.path.join(tmp, "run.log")
        subprocess.run([adam, "logs", "candump", log, "--out", dump], check=True)
        with open(dump) as f:
            frames = [fr for fr in Parser(f) if fr is not None]

    commands = {}
    config = None
    with open(log, "rb") as f:
        reader = make_reader(f)
        for _, channel, message in reader.iter_messages(topics=["/command"]):
            v = json.loads(message.data)
            commands[v["tick"]] = v
        for att in reader.iter_attachments():
            if att.name == "runtime.toml":
                config = tomllib.loads(att.data.decode())
    if config is None:
        raise SystemExit(f"{log}: no runtime.toml attachment")
    joint_of = {m["id"]: m["joint"] for m in config["leg_motors"]}

    checked = 0
    exchange = -1
    seen = set()
    signals = {"q_des": "q_des_rad", "dq_des": "dq_des_rad_s", "kp": "kp_nm_per_rad",
               "kd": "kd_nm_s_per_rad", "tau_ff": "tau_ff_nm"}
    modes = {"pd": 2, "damping": 1}
    for fr in frames:
        if not 0x100 <= fr.frame_id < 0x180:
            continue
        motor = fr.frame_id - 0x100
        # A motor seen again starts the next exchange.
        if motor in seen or exchange < 0:
            exchange += 1
            seen = set()
        seen.add(motor)
        if exchange == 0:
            continue  # the loop's first exchange sends its initial damping commands
        logged = commands.get(exchange - 1)
        if logged is None or motor not in joint_of:
            continue
        joint = joint_of[motor]
        want = logged[joint]
        msg = db.get_message_by_frame_id(fr.frame_id)
        got = msg.decode(bytes(fr.data), decode_choices=False)
        if got["mode"] != modes[want["mode"]]:
            raise SystemExit(f"exchange {exchange} motor {motor}: mode {got['mode']}, logged {want['mode']}")
        if want["mode"] != "pd":
            checked += 1
            continue
        for name, field in signals.items():
            sig = msg.get_signal_by_name(name)
            x = float(want[field])  # `/command` is motor side already
            x = min(max(x, sig.minimum), sig.maximum)
            if abs(got[name] - x) > sig.scale / 2 + 1e-9:
                raise SystemExit(
                    f"exchange {exchange} motor {motor} ({joint}) {name}: cantools "
                    f"{got[name]}, logged {x} (factor {sig.scale})"
                )
        checked += 1
    if checked == 0:
        raise SystemExit(f"{log}: no command frame checked")
    print(f"{log}: {len(frames)} candump frames read by cantools; {checked} command frames "
          f"decoded with drivers/a1_can.dbc equal the logged /command values")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    ensure_venv()
    main(sys.argv[1], sys.argv[2])
