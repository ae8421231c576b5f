#!/usr/bin/awk -f
# Quality statistics of the tetrahedra in a Gmsh MSH 2.2 ASCII file (POSIX awk; mawk is fine).
# Usage: awk [-v list=0.1] -f tools/meshgen/mesh-quality.awk assets/uterus_myoma.msh
#        (list=Q also prints every tet with q* < Q and its centroid)
# Prints, per physical tag and in total: tet count, volume (min/sum), edge length
# (min/mean/max), radius ratio q* = r_in / R_circ (regular tet = 1/3; min/mean),
# minimum and maximum dihedral angle (degrees), count of inverted tets; and the node count.
function acosd(c) { if (c > 1) c = 1; if (c < -1) c = -1; return atan2(sqrt(1 - c*c), c) * 180 / 3.141592653589793 }
function len(x, y, z) { return sqrt(x*x + y*y + z*z) }
BEGIN { sect = "" }
/^\$Nodes/    { sect = "nodes"; getline; nnodes = $1; next }
/^\$EndNodes/ { sect = ""; next }
/^\$Elements/ { sect = "elems"; getline; next }
/^\$EndElements/ { sect = ""; next }
sect == "nodes" { X[$1] = $2; Y[$1] = $3; Z[$1] = $4; next }
sect == "elems" {
  if ($2 != 4) { other++; next }            # type 4 = 4-node tetrahedron
  nt = $3; tag = $4; o = 3 + nt
  if (tag + 0 > maxtag) maxtag = tag + 0
  v[0] = $(o+1); v[1] = $(o+2); v[2] = $(o+3); v[3] = $(o+4)
  for (i = 0; i < 4; i++) { used[v[i]] = 1; px[i] = X[v[i]]; py[i] = Y[v[i]]; pz[i] = Z[v[i]] }
  # edge vectors from vertex 0
  ax = px[1]-px[0]; ay = py[1]-py[0]; az = pz[1]-pz[0]
  bx = px[2]-px[0]; by = py[2]-py[0]; bz = pz[2]-pz[0]
  cx = px[3]-px[0]; cy = py[3]-py[0]; cz = pz[3]-pz[0]
  # b x c, c x a, a x b
  bcx = by*cz - bz*cy; bcy = bz*cx - bx*cz; bcz = bx*cy - by*cx
  cax = cy*az - cz*ay; cay = cz*ax - cx*az; caz = cx*ay - cy*ax
  abx = ay*bz - az*by; aby = az*bx - ax*bz; abz = ax*by - ay*bx
  det = ax*bcx + ay*bcy + az*bcz            # 6 * signed volume
  vol = det / 6
  if (vol <= 0) inv[tag]++
  a2 = ax*ax+ay*ay+az*az; b2 = bx*bx+by*by+bz*bz; c2 = cx*cx+cy*cy+cz*cz
  nx = a2*bcx + b2*cax + c2*abx; ny = a2*bcy + b2*cay + c2*aby; nz = a2*bcz + b2*caz + c2*abz
  adet = det < 0 ? -det : det
  R = len(nx, ny, nz) / (2 * adet)
  # unit normal of the face opposite vertex k, pointing away from vertex k (outward)
  area = 0
  for (k = 0; k < 4; k++) {
    i0 = (k+1)%4; i1 = (k+2)%4; i2 = (k+3)%4
    ux = px[i1]-px[i0]; uy = py[i1]-py[i0]; uz = pz[i1]-pz[i0]
    wx = px[i2]-px[i0]; wy = py[i2]-py[i0]; wz = pz[i2]-pz[i0]
    fx = uy*wz - uz*wy; fy = uz*wx - ux*wz; fz = ux*wy - uy*wx
    # orient away from vertex k
    s = fx*(px[i0]-px[k]) + fy*(py[i0]-py[k]) + fz*(pz[i0]-pz[k])
    if (s < 0) { fx = -fx; fy = -fy; fz = -fz }
    fl = len(fx, fy, fz); area += fl / 2
    FX[k] = fx/fl; FY[k] = fy/fl; FZ[k] = fz/fl
  }
  rin = 3 * adet / 6 / area
  q = rin / R
  if (list != "" && q < list + 0) printf "tet %d tag %d q* %.4f centroid %.2f %.2f %.2f\n", $1, tag, q, (px[0]+px[1]+px[2]+px[3])/4, (py[0]+py[1]+py[2]+py[3])/4, (pz[0]+pz[1]+pz[2]+pz[3])/4
  dmin = 180; dmax = 0
  for (i = 0; i < 4; i++) for (j = i+1; j < 4; j++) {
    d = acosd(-(FX[i]*FX[j] + FY[i]*FY[j] + FZ[i]*FZ[j]))
    if (d < dmin) dmin = d; if (d > dmax) dmax = d
  }
  # edge lengths
  emin = 1e300; emax = 0; esum = 0
  for (i = 0; i < 4; i++) for (j = i+1; j < 4; j++) {
    e = len(px[j]-px[i], py[j]-py[i], pz[j]-pz[i]); esum += e
    if (e < emin) emin = e; if (e > emax) emax = e
  }
  split(tag " all", keys, " ")
  for (kk = 1; kk <= 2; kk++) {
    t = keys[kk]; tags[t] = 1
    n[t]++; qs[t] += q; vs[t] += vol; es[t] += esum; ne[t] += 6
    if (!(t in qmin) || q < qmin[t]) qmin[t] = q
    if (!(t in vmin) || vol < vmin[t]) vmin[t] = vol
    if (!(t in dmn) || dmin < dmn[t]) dmn[t] = dmin
    if (!(t in dmx) || dmax > dmx[t]) dmx[t] = dmax
    if (!(t in emn) || emin < emn[t]) emn[t] = emin
    if (!(t in emx) || emax > emx[t]) emx[t] = emax
    if (q < 0.1) bad[t]++
  }
}
END {
  nu = 0; for (u in used) nu++
  printf "nodes %d (used by tets %d), non-tet elements %d\n", nnodes, nu, other + 0
  printf "%-4s %7s %10s %11s %8s %8s %8s %8s %8s %6s %7s %7s %4s\n", "tag", "tets", "vol_min", "vol_sum", "e_min", "e_mean", "e_max", "q*_min", "q*_mean", "q*<.1", "dih_min", "dih_max", "inv"
  for (t = 0; t <= maxtag; t++) if ((t "") in tags) line(t "")
  line("all")
}
function line(t) {
  printf "%-4s %7d %10.4f %11.1f %8.3f %8.3f %8.3f %8.4f %8.4f %6d %7.2f %7.2f %4d\n", t, n[t], vmin[t], vs[t], emn[t], es[t]/ne[t], emx[t], qmin[t], qs[t]/n[t], bad[t]+0, dmn[t], dmx[t], inv[t]+0
}
