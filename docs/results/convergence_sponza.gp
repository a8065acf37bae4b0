# gnuplot docs/results/convergence_sponza.gp (from docs/results): more budget against the error
set terminal pngcairo size 720,420 font ",10"
set output "convergence_sponza.png"
set title "Sponza: indirect block error against the referee, one budget at a time"
set xlabel "budget / default (log)"
set ylabel "8x8 block error"
set logscale x 2
set key top right
set grid
plot "convergence_sponza.dat" index 0 using 2:3 with linespoints title "surfels (16k-128k)", \
     "" index 1 using 2:3 with linespoints title "links (64-256)", \
     "" index 2 using 2:3 with linespoints title "texel density (0.71-1.41x)", \
     "" index 3 using 2:3 with linespoints title "SH bands (2-4)", \
     0.10 with lines dashtype 2 lc rgb "black" title "target 0.10"
