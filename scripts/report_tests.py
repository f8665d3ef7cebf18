"""The paper's tests as the report runs them: for each, its runs at each size (quick, reduced and full
suites), the figures measured from a run's summary.json, the headline error, the paper's claim and how it is
checked. Read by scripts/report.py; run with Debian's /usr/bin/python3."""
import math
import os
import re

from rsph_plot import FARGO3D_PROFILE, fargo3d_l1s, read_csv

SUITES = ("quick", "reduced", "full")
RSPH1, RSPH2, SPH = "RSPH first order", "RSPH second order", "plain SPH"


class Run:
    """One program run: the method it stands for, its size (what the error-cost line runs along), the
    program's flags, and a guess of its cost in core-seconds for the ETA."""

    def __init__(self, method, size, program, args, guess):
        self.method, self.size, self.program, self.args, self.guess = method, size, program, args, guess

    def folder(self, test):
        """runs/<test>/<method>__<flags>, in letters, digits, dots, dashes and underscores."""
        slug = "-".join(str(a).lstrip("-") for a in self.args)
        method = re.sub(r"[^A-Za-z0-9.]+", "-", self.method)
        return os.path.join(test, method + "__" + re.sub(r"[^A-Za-z0-9.-]+", "_", slug))


def rsph_both(size, program, args, guess, second_guess=None):
    """The same run with the first- and the second-order remap."""
    return [Run(RSPH1, size, program, args + ["--remap", "first"], guess),
            Run(RSPH2, size, program, args + ["--remap", "second"], second_guess or guess)]


def pick(suite, quick, reduced, full):
    return {"quick": quick, "reduced": reduced, "full": full}[suite]


def largest(results, *needed):
    """The measures of each method's last (largest) run, or None when a needed method has none."""
    last = {r.method: m for r, s, m in results}
    return last if all(n in last for n in needed) else None


def finite(*values):
    return all(isinstance(v, (int, float)) and math.isfinite(v) for v in values)


# ---------------------------------------------------------------------------------------------------- Sod
def sod_runs(suite):
    runs = []
    for n in pick(suite, [100, 200], [100, 200, 400], [200, 400, 800, 1600]):
        size = f"{n} particles left"
        runs.append(Run(SPH, size, "rsph-sod", ["--method", "sph", "--n-left", n], n / 400))
        runs += rsph_both(size, "rsph-sod", ["--method", "rsph", "--n-left", n], n / 200)
    return runs


def sod_claim(results):
    by = {m: [r for r in results if r[0].method == m] for m in (SPH, RSPH1, RSPH2)}
    if not all(by.values()):
        return None
    ratio = {m: by[m][-1][1]["L1_rho"] / by[m][0][1]["L1_rho"] for m in by}
    worst = max(ratio.values())
    return ("convergence (Sod checks the engine; the paper has no Sod test): L1(rho) falls with resolution for "
            "every method (largest size over smallest, worst method)", worst,
            worst < 1.0)


# ------------------------------------------------------------------------------------------- drifting pulse
def pulse_runs(suite):
    return [r for n in pick(suite, [100], [100, 400], [100, 200, 400, 800])
            for r in rsph_both(f"{n} remaps", "rsph-drifting-pulse",
                               ["--shifts", "0.1,0.5", "--counts", f"0,{n}"], n / 400)]


def pulse_measures(s):
    out = {}
    for shift in ("0.1", "0.5"):
        w = s["cases"][shift]["width_mass"]
        n = max(w, key=int)
        out[f"width growth s={shift} (spacings)"] = w[n] - w["0"]
        out[f"variance per remap / s(1-s), s={shift}"] = (w[n] ** 2 - w["0"] ** 2) / int(n) / (
            float(shift) * (1 - float(shift)))
    return out


def pulse_claim(results):
    first = [m for r, s, m in results if r.method == RSPH1]
    if not first:
        return None
    v = first[-1]["variance per remap / s(1-s), s=0.5"]
    return ("the first-order remap spreads the pulse as a random walk of variance s(1 - s) Delta^2 per remap "
            "(measured over predicted, s = 0.5)", v, abs(v - 1) < 0.15)


# --------------------------------------------------------------------------------------------- linear waves
def wave_runs(suite):
    periods = pick(suite, 20, 100, 100)
    runs = []
    for lam in pick(suite, [12], [12, 24], [12, 24, 48, 96]):
        args = ["--wavelength", lam, "--periods", periods]
        size = f"lambda = {lam} spacings"
        runs += rsph_both(size, "rsph-linear-wave", args + ["--r", 4.25], lam ** 2 * periods / 4e3)
        runs.append(Run("SPH, alpha = 0.1", size, "rsph-linear-wave", args + ["--r", 0, "--alpha", 0.1],
                        lam ** 2 * periods / 4e3))
    for h in (1.2, 1.5):  # plain SPH without viscosity, jittered: linearly stable at h/Delta = 1.2 only
        runs.append(Run(f"{SPH}, h/Delta = {h}", "lambda = 24 spacings", "rsph-linear-wave",
                        ["--wavelength", 24, "--r", 0, "--kernel", "quintic", "--h-over-dx", h, "--jitter", 1e-4,
                         "--periods", 20], 3))
    return runs


def wave_measures(s):
    growth = max(s["velocity_noise_growth"], s["amplitude_growth"], 1 / max(s["amplitude_growth"], 1e-300))
    return {"gamma (eq. 11)": s["gamma"], "phase error": s["phase_error"], "amplitude growth": s["amplitude_growth"],
            "noise growth": s["velocity_noise_growth"], "instability growth": growth}


def wave_claim(results):
    rsph = [m for r, s, m in results if r.method == RSPH1]
    sph = [m for r, s, m in results if r.method == "SPH, alpha = 0.1"]
    stable = [m for r, s, m in results if r.method == f"{SPH}, h/Delta = 1.2"]
    unstable = [m for r, s, m in results if r.method == f"{SPH}, h/Delta = 1.5"]
    claims = []
    if rsph and sph:
        ratio = rsph[0]["gamma (eq. 11)"] / sph[0]["gamma (eq. 11)"]
        claims.append(("RSPH's damping (regularizing every 4.25 wave periods) is small against plain SPH's with "
                       "artificial viscosity alpha = 0.1 (gamma ratio, smallest lambda; below 0.5)",
                       ratio, ratio < 0.5))
    if stable and unstable:
        g12, g15 = stable[0]["instability growth"], unstable[0]["instability growth"]
        claims.append(("plain SPH without viscosity is linearly stable at h/Delta = 1.2 (growth below 2) and "
                       "unstable at 1.5 (growth above 10): growth at 1.5", g15, g12 < 2 and g15 > 10))
    return claims


# ---------------------------------------------------------------------------------------------- strong shock
def shock_runs(suite):
    runs = []
    sizes = pick(suite, [("quick", 256)], [("quick", 256), ("paper", 512)], [("paper", 512), ("paper", 1024)])
    for preset, nx in sizes:
        size = f"{nx} cells along x"
        base = ["--preset", preset] + (["--nx", nx] if preset == "paper" else [])
        guess = 2.3 * (nx / 256) ** 3.7
        runs += rsph_both(size, "rsph-strong-shock", base + ["--method", "rsph"], guess, 1.1 * guess)
        if nx <= 512:
            runs.append(Run(SPH, size, "rsph-strong-shock", ["--preset", preset, "--method", "sph"], 2 * guess))
    return runs


def shock_measures(s):
    return {"L1(rho)": s["L1_rho"], "shock position error": s["shock_position"] - s["shock_position_exact"],
            "penetration fraction": s["penetration_fraction"], "energy error": s["energy_error"]}


def shock_claim(results):
    last = largest(results, RSPH1, SPH)
    if last is None:
        return None
    rsph, sph = last[RSPH1], last[SPH]
    return [("RSPH keeps the 1e10 shock in place with no penetration (RSPH's penetrating fraction; the shock "
             "within 0.01 of the exact position)", rsph["penetration fraction"],
             rsph["penetration fraction"] == 0 and abs(rsph["shock position error"]) < 0.01),
            ("plain SPH lets particles penetrate the contact (fraction beyond it with the left state, above 0.05)",
             sph["penetration fraction"], sph["penetration fraction"] > 0.05)]


# ----------------------------------------------------------------------------------------- Kelvin-Helmholtz
def kh_runs(suite):
    runs = []
    for n in pick(suite, [64], [64, 128], [128, 256, 512]):
        size = f"1/Delta = {n}"
        runs += rsph_both(size, "rsph-kelvin-helmholtz", ["--cells", n], n ** 3 / 2e5, n ** 3 / 1.2e5)
        if n <= 256:
            runs.append(Run(SPH, size, "rsph-kelvin-helmholtz", ["--cells", n, "--method", "sph"], n ** 3 / 5e4))
    return runs


def kh_measures(s):
    return {"amplification by tau_KH": s["amplification"], "1 / amplification": 1 / s["amplification"],
            "growth rate / linear": s["growth_rate"] / s["growth_rate_incompressible"],
            "overturned fraction": s["overturned_fraction"], "mixed area fraction": s["mixed_area_fraction"],
            "pressure error": s["pressure_error"], "energy error": s["energy_error"]}


def kh_claim(results):
    last = largest(results, SPH, RSPH1)
    if last is None:
        return None
    sph, rsph = last[SPH], last[RSPH1]
    blip = sph["pressure error"] / rsph["pressure error"]
    growth = sph["amplification by tau_KH"] / rsph["amplification by tau_KH"]
    return [("without conductivity plain SPH keeps the phases apart with a pressure blip at the contact (Agertz "
             "et al.'s gap, Price's blip): its rms pressure error over RSPH's, above 2", blip, blip > 2),
            ("... and so suppresses the growth at chi = 10, where RSPH's mode grows (Agertz et al.): SPH's "
             "amplification by tau_KH over RSPH's, below 1", growth, growth < 1)]


# ---------------------------------------------------------------------------------------------- viscous ring
def ring_runs(suite):
    """Sizes by h: the quick preset's nu_s = 4.8e-4 at h = 0.06 and 0.04 (the first snapshots only in the
    quick and reduced suites), the paper's h = 0.02, nu_s = 4.8e-5 in the full one."""
    quick = ["--preset", "quick"]
    sizes = pick(suite, [(0.06, quick + ["--h", 0.06, "--taus", "0.054,0.09"], 2)],
                 [(h, quick + ["--h", h, "--taus", "0.054,0.09,0.126"], 3) for h in (0.06, 0.04)],
                 [(0.04, quick, 5), (0.02, ["--max-bin", 3], 5)])
    runs = []
    for h, args, snapshots in sizes:
        guess = 170 * (0.04 / h) ** 3 * (snapshots / 5) ** 1.5 * (10 if h == 0.02 else 1)
        runs += rsph_both(f"h = {h}", "rsph-viscous-ring", args, guess, 1.3 * guess)
        runs.append(Run(SPH, f"h = {h}", "rsph-viscous-ring", args + ["--cycle", 0], 0.5 * guess))
    return runs


def ring_measures(s):
    return {"|nu_eff / nu_s - 1|": abs(s["nu_eff_over_nu_s"] - 1), "nu_eff / nu_s": s["nu_eff_over_nu_s"],
            "noise error": s["noise_error"], "mass error": s["mass_error"]}


def ring_claim(results):
    last = largest(results, RSPH1, SPH)
    if last is None:
        return None
    claims = [("regularization keeps the ring ordered: noise error with c_r = 4 over plain SPH's (below 1)",
               last[RSPH1]["noise error"] / last[SPH]["noise error"],
               last[RSPH1]["noise error"] < last[SPH]["noise error"])]
    if RSPH2 in last:
        ratio = (last[RSPH1]["nu_eff / nu_s"] - 1) / max(abs(last[RSPH2]["nu_eff / nu_s"] - 1), 1e-12)
        claims.append(("the second-order remap cuts the regularization's excess viscosity nu_eff - nu_s "
                       "(first order's over second's, target 3)", ratio, ratio >= 3))
    return claims


# ------------------------------------------------------------------------------------------------ planet disk
def disk_runs(suite):
    sizes = pick(suite, [(["--preset", "quick", "--orbits", 20], 8000, 20)],
                 [(["--preset", "quick", "--orbits", 100], 8000, 100),
                  (["--preset", "quick", "--orbits", 100, "--particles", 16000], 16000, 100)],
                 [(["--resolution", r], n, 100) for r, n in (("low", 48000), ("med", 108000))])
    runs = []
    for args, n, orbits in sizes:
        guess = n * orbits * (n / 8000) ** 0.5 / 7000
        runs += rsph_both(f"{n} particles, {orbits} orbits", "rsph-planet-disk", args + ["--snapshot-every", orbits],
                          guess, 1.2 * guess)
    return runs


def disk_measures(s, folder):
    out = {"gap depth": s["gap_depth"], "orbits": s["orbits"], "mass error": s["mass_error"]}
    if os.path.exists(os.path.join(folder, "profile.csv")):
        prof = read_csv(os.path.join(folder, "profile.csv"))
        l1 = fargo3d_l1s(prof["r"], prof["sigma_over_sigma0"])
        if l1 is not None:
            ref = read_csv(FARGO3D_PROFILE)
            out["gap depth - FARGO3D's"] = s["gap_depth"] - min(
                v for r, v in zip(ref["r"], ref["sigma_over_sigma0"]) if 0.8 <= r <= 1.2)
            out["L1 of the profile against FARGO3D's (0.6-2.0)"] = l1[0]
    return out


def disk_claim(results):
    last = largest(results, RSPH1, RSPH2)
    if last is None:
        return None
    return ("the second-order remap deepens the gap towards the grid code's (second order's depth over first "
            "order's, largest size)", last[RSPH2]["gap depth"] / last[RSPH1]["gap depth"],
            last[RSPH2]["gap depth"] < last[RSPH1]["gap depth"])


# ------------------------------------------------------------------------------------------ Sedov-Taylor
def sedov_runs(suite):
    runs = []
    for n in pick(suite, [16], [16, 24], [16, 32, 48]):
        size = f"{n}^3 particles"
        guess = (n / 16) ** 4
        runs.append(Run(SPH, size, "rsph-sedov", ["--n", n, "--method", "sph"], 2 * guess))
        runs += rsph_both(size, "rsph-sedov", ["--n", n, "--method", "rsph"], guess)
    return runs


def sedov_measures(s):
    return {"L1(rho)": s["L1_rho"], "shock radius error": s["shock_radius_error"],
            "peak density": s["peak_density"], "centre's pressure / exact": s["central_pressure_ratio"],
            "energy error": s["energy_error"]}


def sedov_claim(results):
    last = largest(results, SPH, RSPH1)
    if last is None:
        return None
    sph, rsph = last[SPH], last[RSPH1]
    claims = [("plain SPH keeps the blast's heat in the particles that received it: the centre's pressure over "
               "the exact one (SPH's, above 2; RSPH's below half of it)", sph["centre's pressure / exact"],
               sph["centre's pressure / exact"] > 2 and
               rsph["centre's pressure / exact"] < 0.5 * sph["centre's pressure / exact"])]
    first = [m for r, s, m in results if r.method == RSPH1]
    if len(first) > 1:
        ratio = first[-1]["L1(rho)"] / first[0]["L1(rho)"]
        claims.append(("RSPH converges to the Sedov-Taylor profile: L1(rho) at the largest size over the smallest "
                       "(below 1)", ratio, ratio < 1))
    return claims


# ------------------------------------------------------------------------------------------ the 3D tests
def sod3d_runs(suite):
    runs = []
    for n in pick(suite, [50], [50, 100], [50, 100, 200]):
        size = f"{n} particles left, 4 x 4 across"
        args = ["--dim", 3, "--ny-left", 4, "--n-left", n]
        runs.append(Run(SPH, size, "rsph-sod", args + ["--method", "sph"], 1.6 * (n / 50) ** 2))
        runs += rsph_both(size, "rsph-sod", args + ["--method", "rsph"], 0.6 * (n / 50) ** 2)
    return runs


def sod3d_claim(results):
    last = largest(results, SPH, RSPH1)
    first = [m for r, s, m in results if r.method == RSPH1]
    if last is None or not first:
        return None
    claims = [("RSPH on the cubic lattice tracks the exact solution closer than plain SPH on its 3D lattice "
               "(RSPH's L1(rho) over SPH's at the largest size, below 1)",
               last[RSPH1]["L1(rho)"] / last[SPH]["L1(rho)"], last[RSPH1]["L1(rho)"] < last[SPH]["L1(rho)"])]
    if len(first) > 1:
        ratio = first[-1]["L1(rho)"] / first[0]["L1(rho)"]
        claims.append(("RSPH converges in 3D: L1(rho) at the largest size over the smallest (below 1)", ratio,
                       ratio < 1))
    return claims


def pulse3d_runs(suite):
    cells, counts = pick(suite, (24, "0,8"), (24, "0,8"), (48, "0,100"))
    return rsph_both(f"{cells}^3, {counts.split(',')[-1]} remaps", "rsph-drifting-pulse",
                     ["--dim", 3, "--cells", cells, "--shifts", "0.1,0.5", "--counts", counts],
                     (cells / 24) ** 3 * int(counts.split(",")[-1]) / 4)


def pulse3d_measures(s):
    out = {}
    for shift in ("0.1", "0.5"):
        w = s["cases"][shift]["width_mass_axes"]
        n = max(w, key=int)
        per_axis = [(w[n][k] ** 2 - w["0"][k] ** 2) / int(n) / (float(shift) * (1 - float(shift))) for k in range(3)]
        out[f"variance per remap / s(1-s), s={shift}, worst axis"] = max(per_axis, key=lambda v: abs(v - 1))
        out[f"width growth s={shift} (spacings)"] = s["cases"][shift]["width_mass"][n] - s["cases"][shift][
            "width_mass"]["0"]
    return out


def pulse3d_claim(results):
    first = [m for r, s, m in results if r.method == RSPH1]
    if not first:
        return None
    v = first[-1]["variance per remap / s(1-s), s=0.5, worst axis"]
    return ("the first-order remap spreads the cube on every axis by s(1 - s) Delta^2 per remap (measured over "
            "predicted, s = 0.5, the axis farthest from it)", v, abs(v - 1) < 0.01)


def kh3d_runs(suite):
    runs = []
    for n in pick(suite, [96], [96, 192], [96, 192]):
        size = f"1/Delta = {n}, 8 deep"
        args = ["--dim", 3, "--depth", 8, "--wavelengths", 1, "--cells", n]
        runs += rsph_both(size, "rsph-kelvin-helmholtz", args, 3 * (n / 96) ** 4)
        if suite == "full" and n == 96:
            runs.append(Run(SPH, size, "rsph-kelvin-helmholtz", args + ["--method", "sph"], 150))
    return runs


def kh3d_measures(s):
    return {"amplification by tau_KH": s["amplification"], "1 / amplification": 1 / s["amplification"],
            "growth rate / linear": s["growth_rate"] / s["growth_rate_incompressible"],
            "mixed area fraction": s["mixed_area_fraction"], "pressure error": s["pressure_error"],
            "energy error": s["energy_error"]}


def kh3d_claim(results):
    first = [(r, m) for r, s, m in results if r.method == RSPH1]
    if not first or "192" not in first[-1][0].size:
        return None  # at 1/Delta = 96 the remap's mixing still stops the mode (docs/results/kelvin_helmholtz.md)
    a = first[-1][1]["amplification by tau_KH"]
    return ("RSPH grows the chi = 10 mode of the extruded layer (amplification by tau_KH at 1/Delta = 192, "
            "above 2)", a, a > 2)


def disk3d_runs(suite):
    runs = []
    for n, orbits in pick(suite, [(20000, 2)], [(20000, 2), (50000, 2)], [(20000, 2), (200000, 10)]):
        size = f"{n} particles, {orbits} orbits"
        args = ["--dim", 3, "--particles", n, "--orbits", orbits, "--snapshot-every", orbits]
        guess = n * orbits / 2500
        # measured: 16 min per orbit against RSPH's 1.4 at 200 000 particles (docs/results/planet_disk.md)
        runs.append(Run(SPH, size, "rsph-planet-disk", args + ["--method", "sph"], 10 * guess))
        runs += rsph_both(size, "rsph-planet-disk", args, guess, 1.2 * guess)
    return runs


def disk3d_measures(s, folder):
    out = disk_measures(s, folder)
    out.update({"wake's rms offset from linear theory (rad)": s["wake_rms_offset"],
                "thickness / hydrostatic": s["thickness_final"],
                "|thickness / hydrostatic - 1|": abs(s["thickness_final"] - 1),
                "wall s per orbit": s["wall_seconds_per_orbit"]})
    return out


def disk3d_claim(results):
    first = [m for r, s, m in results if r.method == RSPH1]
    if not first:
        return None
    t = first[-1]["thickness / hydrostatic"]
    return ("RSPH keeps the 3D disk in vertical hydrostatic equilibrium: its mass-weighted rms z/R over the "
            "profile's (RSPH first order, largest size; within 10 % of 1)", t, abs(t - 1) < 0.1)


class Test:
    def __init__(self, key, title, program, runs, measures, headline, claim, figure, reference):
        self.key, self.title, self.program = key, title, program
        self.runs, self.measures, self.headline, self.claim = runs, measures, headline, claim
        self.figure, self.reference = figure, reference


def plain(fn):
    return lambda s, folder: fn(s)


TESTS = [
    Test("sod", "Sod's shock tube", "rsph-sod", sod_runs,
         plain(lambda s: {"L1(rho)": s["L1_rho"], "L1(v)": s["L1_v"], "L1(P)": s["L1_P"],
                          "energy error": s["energy_error"]}),
         "L1(rho)", sod_claim, "sod", "the exact Riemann solution"),
    Test("drifting_pulse", "Drifting pulse (§2.1, Fig. 2)", "rsph-drifting-pulse", pulse_runs, plain(pulse_measures),
         "width growth s=0.5 (spacings)", pulse_claim, "drifting_pulse", "the pulse's initial top hat"),
    Test("linear_wave", "Linear waves (§3.1, Fig. 3)", "rsph-linear-wave", wave_runs, plain(wave_measures),
         "gamma (eq. 11)", wave_claim, "linear_wave", "the undamped wave (gamma = 0)"),
    Test("strong_shock", "Strong shock 1e10 (§3.2, Fig. 4)", "rsph-strong-shock", shock_runs, plain(shock_measures),
         "L1(rho)", shock_claim, "strong_shock", "the exact Riemann solution"),
    Test("kelvin_helmholtz", "Kelvin-Helmholtz at chi = 10 (§3.3, Fig. 5)", "rsph-kelvin-helmholtz", kh_runs,
         plain(kh_measures), "1 / amplification", kh_claim, "kelvin_helmholtz",
         "linear theory's growth rate 2 pi / tau_KH"),
    Test("viscous_ring", "Viscous ring (§4, Figs. 8-11)", "rsph-viscous-ring", ring_runs, plain(ring_measures),
         "|nu_eff / nu_s - 1|", ring_claim, "viscous_ring", "the analytic ring at the prescribed viscosity"),
    Test("planet_disk", "Planet-disk, Jupiter (§5, Figs. 12-16)", "rsph-planet-disk", disk_runs, disk_measures,
         "gap depth", disk_claim, "planet_disk", "FARGO3D's azimuthal average after 100 orbits (768 x 256, 196 608 cells)"),
    Test("sedov", "Sedov-Taylor blast in 3D", "rsph-sedov", sedov_runs, plain(sedov_measures), "L1(rho)",
         sedov_claim, "sedov", "the self-similar solution (xi0 from its energy integral)"),
    Test("sod3d", "Sod's shock tube in 3D", "rsph-sod", sod3d_runs,
         plain(lambda s: {"L1(rho)": s["L1_rho"], "L1(v)": s["L1_v"], "L1(P)": s["L1_P"],
                          "energy error": s["energy_error"]}),
         "L1(rho)", sod3d_claim, "sod", "the exact Riemann solution"),
    Test("drifting_pulse_3d", "Drifting pulse in 3D (a cube along the diagonal)", "rsph-drifting-pulse",
         pulse3d_runs, plain(pulse3d_measures), "width growth s=0.5 (spacings)", pulse3d_claim, "drifting_pulse",
         "the cube's initial top hat"),
    Test("planet_disk_3d", "A planet in a 3D disk (H/R = 0.05, the 2D disk's Sigma)", "rsph-planet-disk",
         disk3d_runs, disk3d_measures, "wake's rms offset from linear theory (rad)", disk3d_claim, "planet_disk",
         "the wake of linear theory (Ogilvie & Lubow 2002) and the vertically isothermal equilibrium"),
    Test("kelvin_helmholtz_3d", "Kelvin-Helmholtz at chi = 10 in 3D (extruded along z)", "rsph-kelvin-helmholtz",
         kh3d_runs, plain(kh3d_measures), "1 / amplification", kh3d_claim, "kelvin_helmholtz",
         "linear theory's growth rate 2 pi / tau_KH"),
]
