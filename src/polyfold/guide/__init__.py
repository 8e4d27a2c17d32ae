"""The assembly guide: the build order from the pieces, seams and verified folding paths
(`order`, `motion`), its pictures (`pictures`) and the guide itself (`guide.build_guide`), which
make writes as guide.pdf and into instructions.html."""
