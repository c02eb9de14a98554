# Sourced by scripts/bench.sh and scripts/bench_mpi.sh: LAMMPS PERI's input for the cubic
# lattice benchmark, the same problem as Breccia's bench case (E 22.35 GPa, nu 1/4:
# K = 14.9 GPa, G = 8.94 GPa; density 2200; delta = 3.015 dx; a tiny random velocity).
# write_lammps_lattice_input FILE MODEL(pmb|lps) N DX STEPS
write_lammps_lattice_input() {
  local file=$1 model=$2 n=$3 dx=$4 steps=$5 delta coeff
  delta=$(awk -v dx="$dx" 'BEGIN{print 3.015*dx}')
  if [ "$model" = pmb ]; then
    coeff="pair_style peri/pmb
pair_coeff * * $(awk -v K=14.9e9 -v d="$delta" 'BEGIN{printf "%.6e", 18*K/(3.14159265358979*d^4)}') $delta 0.01 0.0"
  else
    coeff="pair_style peri/lps
pair_coeff * * 14.9e9 8.94e9 $delta 0.01 0.0"
  fi
  cat > "$file" <<LMP
units si
boundary s s s
atom_style peri
atom_modify map array
lattice sc $dx
region box block 0 $((n-1)) 0 $((n-1)) 0 $((n-1))
create_box 1 box
create_atoms 1 region box
$coeff
set group all density 2200
set group all volume $(awk -v dx="$dx" 'BEGIN{printf "%.6e", dx^3}')
velocity all create 1e-3 4928459 dist gaussian
neighbor $(awk -v dx="$dx" 'BEGIN{print 0.1*dx}') bin
timestep 1.0e-8
fix 1 all nve
run 0
run $steps
LMP
}
