#!/usr/bin/python3
"""pd2lmp.py -- write a pd model or run file as a LAMMPS peri/pmb or peri/lps scene.

Usage:
  /usr/bin/python3 tests/lammps/pd2lmp.py [options] INPUT.h5 -d DATA -i INPUT.lmp

From a pd-h5 file (pd-bonds' model.h5 or pd-run's run.h5) write
  DATA       a LAMMPS data file, atom_style peri
             (columns: atom-ID atom-type volume density x y z), with
             atom-ID = /particles/id and every number printed with %.17g,
             so LAMMPS reads bit-identical reference positions;
  INPUT.lmp  a LAMMPS input script for the same scene: units si,
             boundary s s s, atom_style peri, lattice sc SPACING (peri/pmb
             takes its lattice constant, hence the node radius and the
             partial-volume width, from it), pair_style peri/pmb, fix nve,
             fix indent sphere with its centre moving through equal-style
             variables exactly as in the seed script
             (variable y equal "v_y0 + step*dt*v_vy"), compute damage/atom,
             and a dump of id x y z vx vy vz c_damage every N steps,
             sorted by id and printed with %.17g.

Every scene parameter is taken from the file's /scene (a run file) when it
has one, the horizon from /bonds, the spacing from /particles; any option
given here overrides it.  A model file without /scene needs them all.

LAMMPS peri/pmb always has contact (its short-range forces) and failure;
a scene without --failure is written with s00 = 1e300, alpha = 0 (no bond
ever breaks); a scene without --contact cannot be written (LAMMPS would
add contact forces pd does not have) unless --allow-contact is given.

With --model lps (or a run file whose /scene says model lps) the pair
style is peri/lps with pair_coeff K G horizon s00 alpha (--bulk-modulus,
--shear-modulus); LAMMPS's influence function is 1/r, so a pd run with
another --influence cannot be written.  --model ves adds lambda and tau
(--ves-lambda, --ves-tau: peri/ves), --model eps the yield stress
(--yield-stress: peri/eps).

Run the result with: lmp -in INPUT.lmp -log none -screen none
(the dump goes to the file given by --dump, default dump.lmp, relative to
the directory LAMMPS runs in).
"""
import argparse
import math
import sys

import h5py
import numpy as np


def fmt(x):
    """A float that strtod reads back bit for bit."""
    return "%.17g" % float(x)


def floats(text, n, what):
    try:
        v = [float(t) for t in text.split(",")]
    except ValueError:
        v = []
    if len(v) != n:
        raise SystemExit("pd2lmp.py: error: %s needs %d comma-separated numbers" % (what, n))
    return v


def main(argv):
    ap = argparse.ArgumentParser(
        prog="pd2lmp.py",
        description="Write a pd-h5 model/run file as a LAMMPS peri/pmb data file and input script.")
    ap.add_argument("input", help="pd-h5 file (model.h5 or run.h5)")
    ap.add_argument("-d", "--data", required=True, help="LAMMPS data file to write")
    ap.add_argument("-i", "--lmp-input", required=True, help="LAMMPS input script to write")
    ap.add_argument("--dump", default="dump.lmp", help="dump file named in the script (default dump.lmp)")
    ap.add_argument("--c", type=float, help="micromodulus c, N/m^6")
    ap.add_argument("--bulk-modulus", type=float, help="bulk modulus K, Pa (c = 18K/(pi delta^4))")
    ap.add_argument("--model", choices=("pmb", "lps", "ves", "eps"),
                    help="material model (default: /scene's, or pmb)")
    ap.add_argument("--shear-modulus", type=float, help="shear modulus G, Pa (lps, ves)")
    ap.add_argument("--ves-lambda", type=float, help="viscous fraction lambda (ves: m_lambdai)")
    ap.add_argument("--ves-tau", type=float, help="relaxation time tau, s (ves: m_taubi)")
    ap.add_argument("--yield-stress", type=float, help="yield stress, Pa (eps)")
    ap.add_argument("--horizon", type=float, help="horizon delta, m (default /bonds horizon)")
    ap.add_argument("--spacing", type=float, help="lattice constant, m (default /particles spacing)")
    ap.add_argument("--failure", metavar="S00,ALPHA", help="critical stretch parameters")
    ap.add_argument("--no-failure", action="store_true", help="no bond breaks (s00 = 1e300, alpha = 0)")
    ap.add_argument("--indenter", metavar="[sphere,]X,Y,Z,R,K,VX,VY,VZ",
                    help="spherical indenter as pd-run's --indenter")
    ap.add_argument("--no-indenter", action="store_true", help="no indenter")
    ap.add_argument("--dt", type=float, help="time step, s")
    ap.add_argument("--steps", type=int, help="number of steps")
    ap.add_argument("--every", type=int, help="dump every N steps (default: steps)")
    ap.add_argument("--skin", type=float, default=0.001, help="neighbor skin, m (default 0.001)")
    ap.add_argument("--allow-contact", action="store_true",
                    help="write the scene even if pd's run has no --contact")
    a = ap.parse_args(argv)

    with h5py.File(a.input, "r") as h:
        P = h["particles"]
        x = np.asarray(P["position"][...], dtype=np.float64)
        vol = np.asarray(P["volume"][...], dtype=np.float64)
        rho = np.asarray(P["density"][...], dtype=np.float64)
        ids = np.asarray(P["id"][...], dtype=np.int64)
        mat = np.asarray(P["material"][...]) if "material" in P else np.zeros(len(ids), np.int32)
        spacing = a.spacing if a.spacing is not None else P.attrs.get("spacing")
        horizon = a.horizon
        if horizon is None and "bonds" in h:
            horizon = h["bonds"].attrs.get("horizon")
        sc = dict(h["scene"].attrs) if "scene" in h else {}

    def scene(key):
        v = sc.get(key)
        if isinstance(v, bytes):
            v = v.decode()
        return v

    effects = str(scene("effects") or "")
    has_scene = bool(sc)

    model = a.model or str(scene("model") or "pmb")
    K = a.bulk_modulus if a.bulk_modulus is not None else scene("bulk_modulus")
    G = a.shear_modulus if a.shear_modulus is not None else scene("shear_modulus")
    lam = a.ves_lambda if a.ves_lambda is not None else scene("ves_lambda")
    tau = a.ves_tau if a.ves_tau is not None else scene("ves_tau")
    if model == "ves" and (lam is None or tau is None):
        raise SystemExit("pd2lmp.py: error: ves needs --ves-lambda and --ves-tau")
    ys = a.yield_stress if a.yield_stress is not None else scene("yield_stress")
    if model == "eps" and ys is None:
        raise SystemExit("pd2lmp.py: error: eps needs --yield-stress")
    if model in ("lps", "ves", "eps"):
        if K is None or G is None:
            raise SystemExit("pd2lmp.py: error: %s needs --bulk-modulus and --shear-modulus" % model)
        if str(scene("influence") or "1/r") != "1/r":
            raise SystemExit("pd2lmp.py: error: LAMMPS peri/lps has the influence function 1/r only")
    # micromodulus
    c = a.c
    if c is None and a.bulk_modulus is not None:
        if horizon is None:
            raise SystemExit("pd2lmp.py: error: --bulk-modulus needs the horizon")
        c = 18.0 * a.bulk_modulus / (math.pi * float(horizon) ** 4)
    if c is None:
        c = scene("c")
    # failure
    if a.no_failure:
        s00, alpha = 1e300, 0.0
    elif a.failure is not None:
        s00, alpha = floats(a.failure, 2, "--failure")
    elif has_scene and "failure" in effects:
        s00, alpha = scene("s00"), scene("alpha")
    elif has_scene:
        s00, alpha = 1e300, 0.0
    else:
        s00 = alpha = None
    # indenter
    ind = None
    if a.indenter is not None and not a.no_indenter:
        t = a.indenter[len("sphere,"):] if a.indenter.startswith("sphere,") else a.indenter
        ind = floats(t, 8, "--indenter")
    elif not a.no_indenter and "indenter" in effects and scene("indenter") is not None:
        ind = [float(v) for v in np.asarray(scene("indenter")).ravel()]
    dt = a.dt if a.dt is not None else scene("dt")
    steps = a.steps if a.steps is not None else scene("steps")
    every = a.every if a.every is not None else scene("every")
    if not every:
        every = steps

    if model in ("lps", "ves", "eps"):
        c = 0.0  # not used by peri/lps, peri/ves or peri/eps
    missing = [n for n, v in (("--c", c), ("--horizon", horizon), ("--spacing", spacing),
                              ("--failure", s00), ("--dt", dt), ("--steps", steps))
               if v is None]
    if missing:
        raise SystemExit("pd2lmp.py: error: %s not in %s; give %s"
                         % (", ".join(missing), a.input, " ".join(missing)))
    if has_scene and "contact" not in effects and not a.allow_contact:
        raise SystemExit("pd2lmp.py: error: the pd run has no --contact, but LAMMPS peri/pmb "
                         "always has contact forces (use --allow-contact to write it anyway)")
    if np.any(mat != mat.flat[0]):
        print("pd2lmp.py: warning: several materials; all become LAMMPS atom type 1",
              file=sys.stderr)

    # box: the body plus a margin (shrink-wrapped anyway: boundary s s s)
    lo, hi = x.min(axis=0), x.max(axis=0)
    margin = 2.0 * float(horizon) + 2.0 * float(spacing)
    order = np.argsort(ids, kind="stable")
    with open(a.data, "w") as f:
        f.write("LAMMPS data file written by pd2lmp.py from %s\n\n" % a.input)
        f.write("%d atoms\n1 atom types\n\n" % len(ids))
        for k, name in enumerate("xyz"):
            f.write("%s %s %slo %shi\n" % (fmt(lo[k] - margin), fmt(hi[k] + margin), name, name))
        f.write("\nAtoms # peri\n\n")
        for i in order:
            f.write("%d 1 %s %s %s %s %s\n" % (ids[i], fmt(vol[i]), fmt(rho[i]),
                                              fmt(x[i, 0]), fmt(x[i, 1]), fmt(x[i, 2])))

    L = []
    L.append("# LAMMPS peri/pmb scene written by pd2lmp.py from %s" % a.input)
    L.append("units           si")
    L.append("dimension       3")
    L.append("boundary        s s s")
    L.append("atom_style      peri")
    L.append("atom_modify     map array")
    L.append("neighbor        %s bin" % fmt(a.skin))
    L.append("neigh_modify    every 1 delay 0 check yes")
    L.append("lattice         sc %s" % fmt(spacing))
    L.append("read_data       %s" % a.data)
    if model == "lps":
        L.append("pair_style      peri/lps")
        L.append("#               <type1> <type2> <K> <G> <horizon> <s00> <alpha>")
        L.append("pair_coeff      * * %s %s %s %s %s"
                 % (fmt(K), fmt(G), fmt(horizon), fmt(s00), fmt(alpha)))
    elif model == "ves":
        L.append("pair_style      peri/ves")
        L.append("#               <type1> <type2> <K> <G> <horizon> <s00> <alpha> <lambda> <tau>")
        L.append("pair_coeff      * * %s %s %s %s %s %s %s"
                 % (fmt(K), fmt(G), fmt(horizon), fmt(s00), fmt(alpha), fmt(lam), fmt(tau)))
    elif model == "eps":
        L.append("pair_style      peri/eps")
        L.append("#               <type1> <type2> <K> <G> <horizon> <s00> <alpha> <yield stress>")
        L.append("pair_coeff      * * %s %s %s %s %s %s"
                 % (fmt(K), fmt(G), fmt(horizon), fmt(s00), fmt(alpha), fmt(ys)))
    else:
        L.append("pair_style      peri/pmb")
        L.append("#               <type1> <type2> <c> <horizon> <s00> <alpha>")
        L.append("pair_coeff      * * %s %s %s %s" % (fmt(c), fmt(horizon), fmt(s00), fmt(alpha)))
    L.append("velocity        all set 0.0 0.0 0.0 sum no units box")
    L.append("fix             F1 all nve")
    if ind is not None:
        X, Y, Z, R, K, VX, VY, VZ = ind
        for name, p0, v in (("x", X, VX), ("y", Y, VY), ("z", Z, VZ)):
            L.append("variable        %s0 equal %s" % (name, fmt(p0)))
            L.append("variable        v%s equal %s" % (name, fmt(v)))
            L.append('variable        %s equal "v_%s0 + step*dt*v_v%s"' % (name, name, name))
        L.append("fix             F2 all indent %s sphere v_x v_y v_z %s units box"
                 % (fmt(K), fmt(R)))
    L.append("compute         C1 all damage/atom")
    L.append("timestep        %s" % fmt(dt))
    L.append("thermo          %d" % every)
    L.append("dump            D1 all custom %d %s id x y z vx vy vz c_C1" % (every, a.dump))
    L.append("dump_modify     D1 sort id format float %.17g")
    L.append("run             %d" % steps)
    with open(a.lmp_input, "w") as f:
        f.write("\n".join(L) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
