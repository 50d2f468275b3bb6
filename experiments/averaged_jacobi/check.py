import sys, os, json, time
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__))); sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests"))
import numpy as np
import avgjacobi
if os.environ.get("AJ", "1") == "1": avgjacobi.install()
import ti_golf as tg
tg.init(None, "f64")
what = sys.argv[1]
t0 = time.time()
if what in ("contacts", "contacts_lively"):
    from pile_pours import run_variant, SAMPLE
    f = run_variant(what)
    q = json.loads(str(f["quality"])); e = f["energy"]; m = float(f["total_mass"])
    kin = e[round(1.0 / SAMPLE):, 0]
    q["mean_kinetic_over_limit"] = float(np.mean(kin) / (0.5 * m * 0.005**2))
    print(json.dumps({k: q[k] for k in ("deepest_overlap", "p99_speed_mps", "outside_bin", "asleep_fraction", "mean_kinetic_over_limit")}))
else:
    sc = tg.load_scene("lab_vacuum", ["world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.5", "contact.layout=contacts"] + [v for v in os.environ.get("AJ_SET", "").split(",") if v])
    r, m = sc.ball.radius, sc.ball.mass
    x = np.array([[0.0, r + 2.0 * r * i, 0.0] for i in range(21)])
    mass = np.full(21, m); mass[-1] = float(os.environ.get("AJ_HEAVY", "100")) * m
    sim = tg.Simulation(sc, x=x, mass=mass)
    sim.run(t=5.0)
    print("gaps/r", np.round((np.diff(sim.x[:, 1]) - 2 * r) / r * 100, 3).tolist(), "floor", round((sim.x[0,1]-r)/r*100,3), "vy", np.round(sim.v[:,1]*1000,3).tolist()[-3:], "status", sim.status.tolist()[:3])
    print(json.dumps({"sink_over_r": float((x[-1, 1] - sim.x[-1, 1]) / r), "min_gap_over_2r": float(np.min(np.diff(sim.x[:, 1])) / (2 * r)), "lateral": float(np.abs(sim.x[:, [0, 2]]).max())}))
print("wall", round(time.time() - t0, 1), what, os.environ.get("AJ_OMEGA"), os.environ.get("AJ_POMEGA"), os.environ.get("AJ_EXTRA"), os.environ.get("AJ_PROJ"))
