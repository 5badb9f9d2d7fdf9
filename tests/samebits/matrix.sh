# tests/samebits/matrix.sh -- the scenes of tests/samebits.bats.
#
# Sourced by a `bash -e` that runs in an empty folder with the programs of
# one build first on PATH: `scene_NAME` runs the pipeline of scene NAME,
# pd-lattice > lattice.h5, pd-bonds > model.h5, pd-run > RUN.h5 with its log
# in RUN.log, pd-damage on every run (RUN-damage.h5 and its table
# RUN-damage.txt), pd-crack-tip on the plate (RUN-tip.txt).  Every file the
# scene leaves is compared with the other build's (samebits_compare in the
# bats file): *.h5 with h5same.py, *.log without its wall-clock line, the
# rest byte for byte.
#
# Each scene is small (625 to 1681 particles, 40 to 100 steps, 3 to 5
# frames) and names its thread count (it is in /scene).  The 3-D bodies are
# 25 particles long along x, so that the lattice stencil's rows take one
# AVX-512 tile of 16 and a last one moved back over it (on a processor with
# AVX-512; elsewhere PD_NO_AVX512=1 changes nothing but is run anyway).

DX=0.001
RHO=2200
DELTA=0.0030001
K=14.9e9
G=6e9

# A bar of 25 x 7 x 7 particles (24 x 6 x 6 mm), with the sets of its end
# layers and of the whole bar.
BAR=(--spacing $DX --density $RHO --box 0,0.024,0,0.006,0,0.006)
BAR_SETS=(--set left=box,-1,0.0025,-1,1,-1,1 --set right=box,0.0215,1,-1,1,-1,1
          --set all=box,-1,1,-1,1,-1,1)
# a stiff sphere touching the top face at mid-length (a scene may not start
# with it inside: pd_scene_inspect), moving down at 200 m/s: 0.5 mm deep
# after about 11 steps, it breaks most bonds below it and presses the
# particles into contact within 30 steps
INDENTER=(--indenter sphere,0.012,0.003,0.009,0.003,1e18,0,0,-200)
BREAK=(--failure 0.0005,0.25 --contact)
PMB=(--bulk-modulus $K)
LPS=(--model lps --bulk-modulus $K --shear-modulus $G)
FRAMES=(--steps 60 --every 20)

# bar [PD-LATTICE OPTION]...: lattice.h5 and model.h5 of the bar.
bar() {
    pd-lattice -q "${BAR[@]}" "$@" -o lattice.h5
    pd-bonds -q --horizon $DELTA lattice.h5 -o model.h5
}

# pdrun NAME PD-RUN OPTION...: NAME.h5 from model.h5, the log NAME.log, and
# pd-damage's NAME-damage.h5 and table NAME-damage.txt.
pdrun() {
    local name=$1
    shift
    pd-run "$@" model.h5 -o "$name.h5" 2>"$name.log"
    damage "$name"
}

damage() {
    pd-damage "$1.h5" -o "$1-damage.h5" >"$1-damage.txt"
}

scene_pmb_list() {
    bar
    pdrun list "${PMB[@]}" "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --bond-list --threads 1
}

scene_pmb_stencil() {
    bar
    pdrun one "${PMB[@]}" "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 1
    pdrun two "${PMB[@]}" "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 2
}

scene_pmb_stencil_no_avx512() {
    bar
    PD_NO_AVX512=1 pdrun seg "${PMB[@]}" "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 1
}

scene_lps_list() {
    bar
    pdrun list "${LPS[@]}" "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --bond-list --threads 1
}

scene_lps_stencil() {
    bar
    pdrun one "${LPS[@]}" "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 1
    pdrun two "${LPS[@]}" "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 2
}

scene_ves() {
    bar
    pdrun one --model ves --bulk-modulus $K --shear-modulus $G --ves-lambda 0.5 --ves-tau 1e-6 \
        "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 1
    pdrun two --model ves --bulk-modulus $K --shear-modulus $G --ves-lambda 0.5 --ves-tau 1e-6 \
        "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 2
}

scene_eps() {
    bar
    # a yield stress low enough for the indented particles to yield
    pdrun one --model eps --bulk-modulus $K --shear-modulus $G --yield-stress 5e6 --influence 1 \
        "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 1
}

scene_projectile() {
    bar
    # a 1 g sphere at 50 m/s onto the top face, with the default stiffness,
    # next to the indenter
    pdrun both "${PMB[@]}" "${BREAK[@]}" "${INDENTER[@]}" "${FRAMES[@]}" --threads 1 \
        --projectile sphere,0.005,0.003,0.0085,0.002,0.001,0,0,-50
    pdrun alone "${PMB[@]}" "${BREAK[@]}" "${FRAMES[@]}" --threads 1 \
        --projectile sphere,0.005,0.003,0.0085,0.002,0.001,0,0,-200,1e19
}

# the bar pulled at its right end (a velocity ramp), its left end held by a
# displacement, and a pulse of body force on the whole bar
BC=(--velocity-bc right,x,points:0,0,2e-6,5 --displacement-bc left,x,0
    --displacement-bc left,y,points:0,0,1e-5,1e-6 --body-force all,z,pulses:1e10,3e-6,-1e10,3e-6)

scene_bc() {
    bar "${BAR_SETS[@]}"
    pdrun one "${PMB[@]}" --failure 0.002,0 "${BC[@]}" "${FRAMES[@]}" --threads 1
    pdrun two "${PMB[@]}" --failure 0.002,0 "${BC[@]}" "${FRAMES[@]}" --threads 2
    pdrun lps "${LPS[@]}" --failure 0.002,0 "${BC[@]}" "${FRAMES[@]}" --threads 1
}

# two materials in the bar (material 2 for x > 11.9 mm) with a weak
# interface, a stiffer law for material 1, pulled apart
scene_materials() {
    bar "${BAR_SETS[@]}" --material-region 2=box,0.0119,1,-1,1,-1,1
    pdrun laws "${PMB[@]}" --failure 0.002,0 --material 1,K=2e10,s00=0.003 \
        --interface 1,2,K=$K,s00=0.0005 --velocity-bc left,x,-5 --velocity-bc right,x,5 \
        "${FRAMES[@]}" --threads 1
    pdrun mix "${PMB[@]}" --failure 0.002,0 --velocity-bc left,x,-5 --velocity-bc right,x,5 \
        --material 2,c=2e21 "${FRAMES[@]}" --threads 1
}

scene_fibre() {
    bar
    pdrun one --failure 0.0005,0.25 --contact --fibre 1,1,0,3e21,1e21,0.001,0.0004 \
        "${INDENTER[@]}" "${FRAMES[@]}" --threads 1
}

# a 2-D plate of 41 x 41 particles (20 mm, 0.5 mm spacing, 1 mm thick) with
# a pre-crack from its left edge to the centre, opened by a wedge that
# starts touching the left edge
scene_plate() {
    pd-lattice -q --dimension 2 --thickness 0.001 --spacing 0.0005 --density 8000 \
        --box -0.01,0.01,-0.01,0.01,0,0 -o lattice.h5
    pd-bonds -q --horizon 0.0015001 --crack segment,-0.011,0,0,0 lattice.h5 -o model.h5
    pdrun two --youngs-modulus 192e9 --failure-energy 50 --fields energy,stress \
        --indenter sphere,-0.012,0,0,0.002,1e17,400,0,0 --steps 100 --every 25 --threads 2
    pd-crack-tip two-damage.h5 >two-tip.txt
    pd-damage --no-precrack two.h5 -o two-noprecrack.h5 >two-noprecrack.txt
}

# an irregular body (bond lists): stress and energy fields
scene_perturbed() {
    pd-lattice -q "${BAR[@]}" --perturb 1e-4 --seed 7 -o lattice.h5
    pd-bonds -q --horizon $DELTA lattice.h5 -o model.h5
    # the indenter 0.1 mm higher: sites stand up to 0.1 mm above the face
    local above=(--indenter sphere,0.012,0.003,0.0091,0.003,1e18,0,0,-200)
    pdrun one "${PMB[@]}" "${BREAK[@]}" "${above[@]}" "${FRAMES[@]}" --fields energy,stress \
        --threads 1
    pdrun two "${PMB[@]}" "${BREAK[@]}" "${above[@]}" "${FRAMES[@]}" --fields energy,stress \
        --threads 2
    pdrun lps "${LPS[@]}" "${BREAK[@]}" "${above[@]}" "${FRAMES[@]}" --fields stress --threads 1
}

# restart: 40 steps, then 40 more from the run's last frame
restart() {
    local name=$1
    shift
    pdrun "$name" "$@" --steps 40 --every 20
    pd-run --restart "$name.h5" --steps 40 --every 20 -o "$name-cont.h5" 2>"$name-cont.log"
    damage "$name-cont"
}

scene_restart() {
    bar "${BAR_SETS[@]}"
    restart stencil "${PMB[@]}" "${BREAK[@]}" "${INDENTER[@]}" --threads 2
    restart list "${LPS[@]}" "${BREAK[@]}" "${INDENTER[@]}" --bond-list --threads 1
    restart bc "${PMB[@]}" --failure 0.002,0 "${BC[@]}" --threads 1
}
