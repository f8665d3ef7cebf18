#!/usr/bin/python3
"""A model of rsph's parallel efficiency on P ranks, from figures measured on the 2-core development machine
(docs/performance.md, "Many ranks") and stated assumptions about a cluster's network, projected to 64, 512
and 4096 ranks for a 3D disk of 1e7 and 1e8 particles. It prints a Markdown table and, with --check, the
model's halo fractions beside the ones measured at 2 and 4 ranks.

Per step and rank, with n = N / P particles:
  compute   t_c = n c                          c: measured seconds per particle-step (one thread)
  halo      H = k_h n^(2/3)                    particles; k_h fitted to the measured halo fractions
  remap     by owners (the first-order remap onto a fixed lattice): t_r = c_r n every T steps, a rank builds
            the old cells of its own particles; it sends the sums of the new cells on its surface,
            S_1 = ((1 + 2 / L)^3 - 1) n, and answers for the two layers of the hand-on, S_2, at b_s bytes each,
            in 3 more exchanges; it gathers the particles within R_o = 4 h (its own cells' generators and
            the keepers of the new cells it asks about; measured: one remap in 41 gathers farther, on the disk)
            widened (second order, multi-level lattices, rings): t_r = (c_r n)(1 + 2 R_c / L)^3, a rank builds
            the old cells of its part widened by R_c = 6 h (h = 1.2 spacings), L = n^(1/3) spacings
  messages  t_m = m_x alpha (log2 P + k) + m_r alpha log2 P + b (H + H_r / T) / beta
            H_r = ((1 + 2 R_r / L)^3 - 1) n: the particles a remap gathers, within R_r = R_o by owners and
            12 h widened
            m_x exchanges (Comm::exchange: a reduction telling each rank how many messages come, alpha log2 P,
            then one message to and from each of the k ranks it trades with, k = min(P - 1, 26) as for cubes),
            m_r reductions (alpha log2 P each), b bytes per halo particle per step
  imbalance a fixed 5 % (Zoltan's tolerance)
  efficiency = t_c' / (t_c' + t_r' + t_m + imbalance), primes: what one rank of the serial run would do.
"""
import argparse
import math

# measured (docs/performance.md): rsph-sedov 3D, one thread
C_SPH = 11.39 / (92 * 32768)     # seconds per particle-step, grad-h SPH
C_RSPH = (6.53 - 0.646) / (119 * 32768)  # RSPH's SPH step
REMAP = 0.646 / 4 / 32768        # seconds per particle per remap (first order, cubic lattice)
STEPS_PER_REMAP = 119 / 4
BYTES_PER_HALO = 155.0           # measured: 2.97e6 bytes per step for 19 200 halo particles (n = 40, P = 2)
EXCHANGES = 3                    # per step, measured (summary.json's exchanges_per_step: 2.1 SPH, 3.3 RSPH, 3D
                                 # blast at 2 ranks): a halo build and a refresh, each one message whatever the fields
NEIGHBOURS = 26                  # the ranks a rank trades with (a cube's face, edge and corner neighbours)
REDUCTIONS = 12                  # per step, measured (collectives_per_step: 12.2 SPH, 11.6 RSPH): balance (2), time
                                 # step, h_max, the bounds, the h solver's fits, due, check, totals (2)
REMAP_CELLS_IN_H = 6             # a remap builds the old cells of its own particles and of others within 6 h
REMAP_HALO_IN_H = 12             # and gathers every particle within 12 h (the generators those cells need)
OWNER_HALO_IN_H = 4              # by owners: gathers within 4 h (DecompositionParams::owner_reach_in_h)
BYTES_PER_SUM = 8 * 7            # by owners: a new cell's flat index, m, m v, E and volume
OWNER_EXCHANGES = 3              # by owners: the parts, the window's request and its answer
# measured halo fractions of rsph-sedov --method sph --r-end 0.12, 3D, at P = 2 and 4 (n = N / P)
MEASURED = [(16, 2, 0.625), (24, 2, 0.417), (32, 2, 0.375), (40, 2, 0.30),
            (16, 4, 1.64), (24, 4, 1.01), (32, 4, 0.89), (40, 4, 0.69)]
# assumed network of a cluster (not measured here)
ALPHA = 2e-6    # seconds per message
BETA = 10e9     # bytes per second per rank


def fit_halo():
    """k_h of H / n = k_h n^(-1/3), least squares over the 4-rank runs, whose parts have neighbours on more sides,
    as in a large run (2-rank slabs touch one neighbour, through two faces)."""
    pts = [(n ** 3 / P, f) for n, P, f in MEASURED if P == 4]
    return sum(f * m ** (-1 / 3) for m, f in pts) / sum(m ** (-2 / 3) for m, f in pts)


def efficiency(N, P, k_h, rsph=True, by_owners=True):
    n = N / P
    c = C_RSPH if rsph else C_SPH
    t_c = n * c
    H = min(k_h * n ** (2 / 3), N - n)
    log_p = math.log2(max(P, 2))
    exchange = ALPHA * (log_p + min(P - 1, NEIGHBOURS))
    t_m = EXCHANGES * exchange + REDUCTIONS * ALPHA * log_p + BYTES_PER_HALO * H / BETA
    t_r, t_r_serial = 0.0, 0.0
    if rsph:
        L = n ** (1 / 3)
        t_r_serial = REMAP * n / STEPS_PER_REMAP
        if by_owners:
            t_r = t_r_serial
            surface = min(((1 + 2 / L) ** 3 - 1) * n, N - n)
            window = min(((1 + 4 / L) ** 3 - 1) * n, N - n)
            t_m += (OWNER_EXCHANGES * exchange + BYTES_PER_SUM * (surface + window) / BETA) / STEPS_PER_REMAP
        else:
            t_r = t_r_serial * min((1 + 2 * REMAP_CELLS_IN_H * 1.2 / L) ** 3, P)
        reach = OWNER_HALO_IN_H if by_owners else REMAP_HALO_IN_H
        gathered = min(((1 + 2 * reach * 1.2 / L) ** 3 - 1) * n, N - n)
        t_m += BYTES_PER_HALO * gathered / BETA / STEPS_PER_REMAP
    useful = t_c + t_r_serial
    total = 1.05 * (t_c + t_r) + t_m
    return useful / total, t_c, t_r, t_m, H / n


def remap_set(N, P, by_owners=True):
    """The particles a rank holds during a remap, its own and those it gathers, over its own."""
    n = N / P
    L = n ** (1 / 3)
    reach = OWNER_HALO_IN_H if by_owners else REMAP_HALO_IN_H
    return 1 + min(((1 + 2 * reach * 1.2 / L) ** 3 - 1) * n, N - n) / n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="the model's halo fractions beside the measured ones")
    a = ap.parse_args()
    k_h = fit_halo()
    if a.check:
        print(f"k_h = {k_h:.2f}")
        for n, P, f in MEASURED:
            m = n ** 3 / P
            print(f"n = {n}^3, P = {P}: measured {f:.3f}, model {min(k_h * m ** (-1 / 3), P - 1):.3f}")
    print("| particles | ranks | particles per rank | halo / own | RSPH step by owners: compute, remap, messages "
          "(ms) | efficiency RSPH, by owners | widened | SPH | a remap's set / own, by owners | widened |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for N in (1e7, 1e8):
        for P in (64, 512, 4096):
            e, t_c, t_r, t_m, frac = efficiency(N, P, k_h, True)
            e_wide = efficiency(N, P, k_h, True, False)[0]
            e_sph = efficiency(N, P, k_h, False)[0]
            print(f"| {N:.0e} | {P} | {N / P:.0f} | {frac:.2f} | {1e3 * t_c:.1f}, {1e3 * t_r:.1f}, {1e3 * t_m:.1f} | "
                  f"{e:.2f} | {e_wide:.2f} | {e_sph:.2f} | {remap_set(N, P):.1f} | {remap_set(N, P, False):.1f} |")


if __name__ == "__main__":
    main()
