#!/usr/bin/env python3
"""The fragment sizes blasting practice gives for a charge of a given energy in this block.

Kuznetsov's formula (Kuznetsov 1973, Soviet Mining Science 9:144-148; with Cunningham's
Rosin-Rammler size distribution it is the Kuz-Ram model, Cunningham 1983, 1st Int. Symp. on
Rock Fragmentation by Blasting, Lulea), the empirical relation blasting engineers use for the
median fragment size of a blast:

    x50 [cm] = A q^-0.8 Q^(1/6),   q = Q / V [kg/m3],  Q [kg]

with the charge Q per hole and the specific charge q in kilograms of TNT equivalent
(Cunningham's form with an explosive's relative weight strength RWS against ANFO,
(115 / RWS)^(19/30), is the same for TNT, RWS 115), and the rock factor A, 7 for medium
rock to 13 for hard, weakly fissured rock. The share of the mass in pieces larger than x
follows Cunningham's Rosin-Rammler form R(x) = exp(-ln 2 (x / x50)^n), with the uniformity
index n (usually 0.8-2.2 in bench blasts). All these forms and ranges are recalled from the
literature that quotes them (Ouchterlony 2016, Blasting and Fragmentation 10:1-18, reviews
them), not read in Kuznetsov's or Cunningham's papers.

The charge here is the gas energy a run's history.csv reports (its `gas_work_J` to the end,
or the closed-cavity gas's energy), turned into TNT equivalent at 4.184 MJ/kg (the
definition of the unit). Kuznetsov's formula was fitted to bench blasts of kilograms to
tonnes of explosive per hole: a few grams in a 0.3 m block is three orders of magnitude
below that, so its figures are an indication of scale, not a benchmark.

    python3 kuznetsov_estimate.py --energy 24611        # the full case's gas work at 1 ms
    python3 kuznetsov_estimate.py --energy 1374 --energy 24611 --piece 0.081
"""
import argparse
import math

TNT_J_PER_KG = 4.184e6


def median_size_cm(rock_factor, charge_kg, volume_m3):
    """Kuznetsov's x50 [cm] for a charge [kg TNT] in a rock volume [m3]."""
    q = charge_kg / volume_m3
    return rock_factor * q**-0.8 * charge_kg ** (1.0 / 6.0)


def share_larger(x_cm, x50_cm, n):
    """Cunningham's Rosin-Rammler: the mass share in pieces larger than x."""
    return math.exp(-math.log(2.0) * (x_cm / x50_cm) ** n)


def charge_for_median(rock_factor, x50_cm, volume_m3):
    """The charge [kg TNT] whose x50 is x50_cm: x50 = A V^(1/6) q^(1/6 - 0.8)."""
    q = (x50_cm / (rock_factor * volume_m3 ** (1.0 / 6.0))) ** (1.0 / (1.0 / 6.0 - 0.8))
    return q * volume_m3


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--energy", type=float, action="append", required=True,
                    help="the charge's energy [J] (repeatable)")
    ap.add_argument("--volume", type=float, default=0.027, help="the block's volume [m3] (0.3 m cube)")
    ap.add_argument("--rock-factor", type=float, nargs="+", default=[7.0, 10.0, 13.0], help="A")
    ap.add_argument("--uniformity", type=float, nargs="+", default=[1.0, 1.5, 2.0], help="n")
    ap.add_argument("--piece", type=float, default=0.081,
                    help="a large piece's edge [m] (2%% of a 0.3 m cube: 0.081 m)")
    a = ap.parse_args()
    piece_cm = 100.0 * a.piece
    for energy in a.energy:
        charge = energy / TNT_J_PER_KG
        print(f"energy {energy:.0f} J = {charge * 1e3:.2f} g TNT, specific charge {charge / a.volume:.3f} kg/m3")
        for A in a.rock_factor:
            x50 = median_size_cm(A, charge, a.volume)
            shares = ", ".join(f"n {n:g}: {100 * share_larger(piece_cm, x50, n):.0f}%" for n in a.uniformity)
            print(f"  A {A:g}: x50 {10 * x50:.0f} mm; mass in pieces over {10 * piece_cm:.0f} mm: {shares}")
    for A in a.rock_factor:
        charge = charge_for_median(A, piece_cm, a.volume)
        print(f"x50 = {10 * piece_cm:.0f} mm at A {A:g}: {charge * 1e3:.1f} g TNT = {charge * TNT_J_PER_KG / 1e3:.1f} kJ")


if __name__ == "__main__":
    main()
