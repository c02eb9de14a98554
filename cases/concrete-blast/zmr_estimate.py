#!/usr/bin/env python3
"""The fragment size the block's expansion rate implies, by Zhou, Molinari & Ramesh (2006).

The block is read as expanding about the hole's axis with the homogeneous velocity field
v = rate x r (r the distance from the axis), whose kinetic energy over the block's square
section of side a and height h is  K = rho rate^2 h a^4 / 12,  so  rate = sqrt(12 K / (rho h a^4)).
That rate is the hoop strain rate everywhere. Zhou, Molinari & Ramesh (Appl Phys Lett 88,
261918, 2006; the form the issue "Quasi-brittle bonds" quotes, which cases/grady-ring tests):

    s = L0 x 4.5 / (1 + 4.5 e^(2/3)),  L0 = E G0 / sigma_t^2,  e = rate / e0,
    e0 = c sigma_t^3 / (E^2 G0),  c = sqrt(E / rho);

Grady's energy balance, the upper bound at high rates: s_G = (sqrt(24) K_Ic / (rho c rate))^(2/3),
K_Ic = sqrt(E G0). It also prints the largest rate (and kinetic energy) at which the ZMR size
still reaches `--piece` (a large piece's edge).

    python3 zmr_estimate.py --kinetic 6965 [--g0 25] [--strength 3e6] [--piece 0.081]
"""
import argparse
import math


def rate_from_kinetic(kinetic, rho, a, h):
    return math.sqrt(12.0 * kinetic / (rho * h * a**4))


def zmr_size(rate, E, rho, G0, st):
    c = math.sqrt(E / rho)
    L0 = E * G0 / st**2
    e0 = c * st**3 / (E**2 * G0)
    return L0 * 4.5 / (1.0 + 4.5 * (rate / e0) ** (2.0 / 3.0)), L0, e0


def grady_size(rate, E, rho, G0):
    c = math.sqrt(E / rho)
    return (math.sqrt(24.0) * math.sqrt(E * G0) / (rho * c * rate)) ** (2.0 / 3.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kinetic", type=float, required=True, help="the block's kinetic energy [J]")
    ap.add_argument("--g0", type=float, default=25.0, help="fracture energy [J/m2] (case.yaml: 25)")
    ap.add_argument("--strength", type=float, default=3.0e6, help="tensile strength [Pa] (case.yaml: 3 MPa)")
    ap.add_argument("--E", type=float, default=34.2e9, help="Young's modulus [Pa]")
    ap.add_argument("--rho", type=float, default=2320.0, help="density [kg/m3]")
    ap.add_argument("--side", type=float, default=0.3, help="the block's side a [m]")
    ap.add_argument("--height", type=float, default=0.3, help="the block's height h [m]")
    ap.add_argument("--piece", type=float, default=0.081,
                    help="a large piece's edge [m] (2%% of a 0.3 m cube: 0.081 m)")
    a = ap.parse_args()
    rate = rate_from_kinetic(a.kinetic, a.rho, a.side, a.height)
    s, L0, e0 = zmr_size(rate, a.E, a.rho, a.g0, a.strength)
    sg = grady_size(rate, a.E, a.rho, a.g0)
    # Largest rate whose ZMR size is still the piece's edge: 1 + 4.5 e^(2/3) = 4.5 L0 / piece.
    x = (4.5 * L0 / a.piece - 1.0) / 4.5
    rate_max = e0 * x**1.5 if x > 0 else 0.0
    kinetic_max = a.rho * a.height * a.side**4 * rate_max**2 / 12.0
    print(f"kinetic {a.kinetic:.0f} J -> hoop strain rate {rate:.1f} /s; L0 {L0 * 1e3:.1f} mm, e0 {e0:.3f} /s, "
          f"e {rate / e0:.1f}")
    print(f"ZMR size {s * 1e3:.1f} mm; Grady's bound {sg * 1e3:.1f} mm")
    print(f"a {a.piece * 1e3:.0f} mm piece needs a rate <= {rate_max:.2f} /s, kinetic energy <= {kinetic_max:.1f} J")


if __name__ == "__main__":
    main()
