# prototype: python port of fp_rig falloff + pose, for iterating on weights
import json, sys, numpy as np
sys.path.insert(0, '/work/wt-rig3/rigs/tools')
import build_rigs as B
from pathlib import Path
DATA = Path('/work/shared/data')

def ss(a, b, x):
    t = np.clip((x - a) / (b - a), 0, 1)
    return t * t * (3 - 2 * t)

def expand(vs):
    out = []
    for e in vs:
        if isinstance(e, list): out.extend(range(e[0], e[1] + 1))
        else: out.append(e)
    return np.array(out, dtype=int)

def side(a, b, o, z, y):
    dz, dy = b[0]-a[0], b[1]-a[1]; l = np.hypot(dz, dy)
    nz, ny = dy/l, -dz/l
    so = (o[0]-a[0])*nz + (o[1]-a[1])*ny
    if so > 0: nz, ny = -nz, -ny
    return (z-a[0])*nz + (y-a[1])*ny

def falloff(r, P):
    j = r['jaw']; f = j['falloff']
    H = 0.5*(np.array(j['hinge']['right'])+np.array(j['hinge']['left']))
    D = P - H; x, y, z = D[:,0], D[:,1], D[:,2]   # axes are identity for ICT
    M = np.array(f['mouth_line']) - H
    mx, my, mz = M[:,0], M[:,1], M[:,2]
    ym = np.interp(x, mx, my); zm = np.interp(x, mx, mz)
    e = np.where(x <= mx[0], mx[0]-x, np.where(x >= mx[-1], x-mx[-1], -np.minimum(x-mx[0], mx[-1]-x)))
    s = ss(-f.get('corner_inset', 0), f['cheek_distance'], e)
    idp = f.get('inner_depth', 0)
    if idp > 0: s = np.maximum(s, ss(idp, 2*idp, zm - z))
    b = f['lip_band'] + (f['cheek_band']-f['lip_band'])*s
    wm = 1 - ss(-b, b, y - ym)
    G = np.array(f['gonion']) - H; Mn = np.array(f['menton']) - H
    C = (0, 0); Gs = (G[2], G[1]); Ms = (Mn[2], Mn[1])
    wb = 1 - ss(0, f['back_band'], side(C, Gs, Ms, z, y))
    wn = 1 - ss(0, f['neck_band'], side(Gs, Ms, C, z, y))
    return wm*wb*wn

def weights(r, V):
    n = len(V); kind = np.zeros(n, int)
    for g in r['regions']:
        k = {'soft':0,'skull':1,'jaw':2}[g['kind']]; kind[expand(g['vertices'])] = k
    w = falloff(r, V.astype(float))
    w[kind == 1] = 0; w[kind == 2] = 1
    ov = r['jaw'].get('weights')
    if ov:
        w[expand(ov['vertices'])] = ov['values']
    return w, kind

def rot(k, a):
    # batched Rodrigues: a array
    c, s = np.cos(a), np.sin(a); t = 1 - c
    R = np.empty((len(a), 3, 3))
    R[:,0,0]=t*k[0]*k[0]+c; R[:,0,1]=t*k[0]*k[1]-s*k[2]; R[:,0,2]=t*k[0]*k[2]+s*k[1]
    R[:,1,0]=t*k[0]*k[1]+s*k[2]; R[:,1,1]=t*k[1]*k[1]+c; R[:,1,2]=t*k[1]*k[2]-s*k[0]
    R[:,2,0]=t*k[0]*k[2]-s*k[1]; R[:,2,1]=t*k[1]*k[2]+s*k[0]; R[:,2,2]=t*k[2]*k[2]+c
    return R

def pose(r, V, w, open_):
    j = r['jaw']; hr = np.array(j['hinge']['right']); hl = np.array(j['hinge']['left'])
    ax = (hl-hr)/np.linalg.norm(hl-hr)
    th = open_*j['open_degrees']*np.pi/180
    R = rot(ax, w*th)
    out = hr + np.einsum('nij,nj->ni', R, V.astype(float)-hr)
    out = out.astype(np.float32)
    out[w == 0] = V[w == 0]
    return out

def write_obj(path, V, F):
    with open(path, 'w') as f:
        f.write(''.join('v %.9g %.9g %.9g\n' % tuple(p) for p in V))
        f.write(''.join('f %d %d %d\n' % (a+1, b+1, c+1) for a, b, c in F))
