# Plot of bench_refine's CSV: gnuplot -e "csv='docs/data/depth_refinement_1080p.csv'" docs/data/depth_refinement_plot.gp
if (!exists("csv")) csv = 'docs/data/depth_refinement_1080p.csv'
if (!exists("png")) png = 'docs/img/depth_refinement_1080p.png'
set terminal pngcairo size 1400,500 font ",11"
set output png
set datafile separator ","
set multiplot layout 1,3 title "Depth refinement, synthetic 1920x1080 street (bench\\_refine)"
set key top right
set grid
set logscale x
set xlabel "seconds (optimiser only)"
set logscale y
set ylabel "objective L = 50 L1 + L2"
plot csv using (strcol(1) eq "adam" || strcol(1) eq "adam_100" || strcol(1) eq "adam_1000" ? $4 : 1/0):5 with lines lw 2 title "Adam lr 2e-4 (paper)", \
     csv using (strcol(1) eq "ceres_lbfgs" ? $4 : 1/0):5 with linespoints pt 7 ps 0.5 lw 2 title "Ceres L-BFGS (Jacobi-scaled)", \
     csv using (strcol(1) eq "ceres_lbfgs_no_jacobi_scaling" ? $4 : 1/0):5 with lines lw 1 dt 2 title "Ceres L-BFGS, no scaling"
unset logscale y
set ylabel "depth AbsRel"
plot csv using (strcol(1) eq "ceres_lbfgs" ? $4 : 1/0):8 with linespoints pt 7 ps 0.5 lw 2 title "Ceres L-BFGS", \
     csv using (strcol(1) eq "adam" || strcol(1) eq "adam_100" || strcol(1) eq "adam_1000" ? $4 : 1/0):8 with points pt 5 ps 1.5 title "Adam 0/100/1000", \
     csv using (strcol(1) eq "raw" ? 0.05 : 1/0):8 with points pt 9 ps 2 title "raw estimate", \
     csv using (strcol(1) eq "filtered" ? 0.05 : 1/0):8 with points pt 11 ps 2 title "filtered"
set ylabel "normal error of the depth, mean deg"
plot csv using (strcol(1) eq "ceres_lbfgs" ? $4 : 1/0):10 with linespoints pt 7 ps 0.5 lw 2 title "Ceres L-BFGS", \
     csv using (strcol(1) eq "adam" || strcol(1) eq "adam_100" || strcol(1) eq "adam_1000" ? $4 : 1/0):10 with points pt 5 ps 1.5 title "Adam 0/100/1000", \
     csv using (strcol(1) eq "filtered" ? 0.05 : 1/0):10 with points pt 11 ps 2 title "filtered"
unset multiplot
