# A scripted ParaView Catalyst Live client (run with pvpython): listens on localhost:PORT, receives
# the simulation's particles, steers it, and disconnects mid-run. What it saw and did goes to a
# JSON report for tests/live/live_test.py to check against the simulation's outputs.
#
# Usage: pvpython live_client.py PORT STEERING_XML REPORT_JSON [--timeout SECONDS]
# Plan (one live step apart, in this order, once particles have arrived):
#   1. gravity := (2, -9.81, 0)          (accepted: tilts gravity to the right)
#   2. viscosity := 50 Pa s              (outside [0, 10]: rejected by the solver)
#   3. pause (Catalyst's own pause), pump events for 2 s noting the steps seen, set
#      artificial_viscosity := 0.05 while paused, continue
#   4. write_checkpoint := 1             (a checkpoint now)
#   5. disconnect after two more live steps (the simulation must go on to the end)
import json
import os
import sys
import time

from paraview.simple import *
from paraview import live

port = int(sys.argv[1])
xml = sys.argv[2]
report_path = sys.argv[3]
timeout = float(sys.argv[sys.argv.index("--timeout") + 1]) if "--timeout" in sys.argv else 60.0

report = {"port": port, "events": [], "particles": None, "particles_step": None, "requests": []}


def save():
    with open(report_path, "w") as f:
        json.dump(report, f, indent=1)


def note(what):
    report["events"].append(what)
    print("live_client:", what, flush=True)
    save()


# The steering proxy's type must be known here too, as in the GUI (Tools > Manage Plugins).
LoadPlugin(xml, remote=False, ns=globals())
link = live.ConnectToCatalyst("localhost", port)
note("listening on localhost:%d" % port)

def set_property(proxy, name, values):
    prop = proxy.GetProperty(name)
    for i, v in enumerate(values):
        prop.SetElement(i, v)


state = {"step": None, "updates": 0}


def on_update(obj, event):
    state["step"] = obj.GetTimeStep()
    state["updates"] += 1


link.AddObserver("UpdateEvent", on_update)

extract = None
plan = ["gravity", "viscosity", "pause", "write_checkpoint", "disconnect", "disconnect"]
last_acted_step = None
deadline = time.time() + timeout
while time.time() < deadline:
    live.ProcessServerNotifications()
    step = state["step"]
    if step is None:
        time.sleep(0.01)
        continue
    pxm = link.GetInsituProxyManager()
    if extract is None and pxm.GetProxy("sources", "particles") is not None:
        extract = live.ExtractCatalystData(link, "particles")
        note("extracting 'particles' at step %d" % step)
    if extract is not None and report["particles"] is None:
        extract.UpdatePipeline()
        n = extract.GetDataInformation().GetNumberOfPoints()
        if n > 0:
            report["particles"] = n
            report["particles_step"] = step
            note("received %d particles at step %d" % (n, step))
        continue
    if report["particles"] is None or step == last_acted_step:
        time.sleep(0.005)
        continue
    # One action per live step.
    last_acted_step = step
    action = plan.pop(0) if plan else "disconnect"
    steering = pxm.GetProxy("sources", "steering")
    if action == "gravity":
        set_property(steering, "gravity", [2.0, -9.81, 0.0])
        steering.UpdateVTKObjects()
        link.PushUpdatedStates()
        report["requests"].append({"name": "gravity", "value": [2.0, -9.81, 0.0], "step": step})
        note("asked gravity = (2, -9.81, 0) at step %d" % step)
    elif action == "viscosity":
        set_property(steering, "viscosity", [50.0])
        steering.UpdateVTKObjects()
        link.PushUpdatedStates()
        report["requests"].append({"name": "viscosity", "value": [50.0], "step": step})
        note("asked viscosity = 50 at step %d" % step)
    elif action == "write_checkpoint":
        set_property(steering, "write_checkpoint", [1])
        steering.UpdateVTKObjects()
        link.PushUpdatedStates()
        report["requests"].append({"name": "write_checkpoint", "value": [1], "step": step})
        note("asked write_checkpoint at step %d" % step)
    elif action == "pause":
        live.PauseCatalyst(link, True)
        t0 = time.time()
        seen = []
        while time.time() - t0 < 2.0:
            live.ProcessServerNotifications()
            if time.time() - t0 > 0.5:  # the pause takes effect at the simulation's next live step
                seen.append(state["step"])
            time.sleep(0.01)
        # An edit while paused: applied at the boundary right after the held step.
        set_property(steering, "artificial_viscosity", [0.05])
        steering.UpdateVTKObjects()
        link.PushUpdatedStates()
        report["requests"].append({"name": "artificial_viscosity", "value": [0.05], "step": state["step"]})
        t1 = time.time()
        while time.time() - t1 < 0.3:
            live.ProcessServerNotifications()
            time.sleep(0.01)
        live.PauseCatalyst(link, False)
        report["pause"] = {"asked_at": step, "steps_seen_while_paused": sorted(set(seen))}
        note("paused at step %d; steps seen while paused: %s; continued" % (step, sorted(set(seen))))
    elif action == "disconnect" and not plan:
        note("disconnecting at step %d" % step)
        report["disconnected_step"] = step
        save()
        sys.stdout.flush()
        os._exit(0)  # the socket closes with the process, as when a GUI user quits
note("timed out after %.0f s (last step %s)" % (timeout, state["step"]))
save()
os._exit(3)
