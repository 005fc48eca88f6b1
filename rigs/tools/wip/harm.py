from check import *
from scipy.spatial import cKDTree
import scipy.sparse as sp, scipy.sparse.linalg as sla
KNN = int(__import__("os").environ.get("KNN", 6))
base = json.load(open('/work/wt-rig3/rigs/ict-facekit.json'))
def make(lo=0.3, hi=0.7, depth=0.8):
    r = json.loads(json.dumps(base))
    r['regions'] = [g for g in r['regions'] if g['name'] not in ('upper_gums', 'lower_gums_tongue', 'mouth_floor', 'palate')]
    w, kind = weights(r, V)
    n = len(V)
    inter = np.r_[np.arange(11248, 13294), np.arange(14062, 17039)]
    isin = np.zeros(n, bool); isin[inter] = True
    du, _ = cKDTree(V[17039:19247]).query(V); dl, _ = cKDTree(V[19247:21451]).query(V)
    t = du / (du + dl)
    f = r['jaw']['falloff']; M = np.array(f['mouth_line'])
    zm = np.interp(V[:,0], M[:,0], M[:,2])
    fixed = ~isin.copy()
    val = w.copy()
    a = isin & (t < lo); b = isin & (t > hi)
    fixed |= a | b
    val[a] = 0; val[b] = 1
    # lining near the lips keeps the skin's falloff
    nearlip = isin & (zm - V[:,2] < depth) & (np.arange(n) < 13294)
    fixed |= nearlip
    val[nearlip] = w[nearlip]
    # graph Laplacian from triangles
    E = np.r_[F[:, [0,1]], F[:, [1,2]], F[:, [2,0]]]
    A = sp.coo_matrix((np.ones(len(E)), (E[:,0], E[:,1])), shape=(n, n)).tocsr()
    T = cKDTree(V[inter]); _, nb = T.query(V[inter], k=KNN)
    I = np.repeat(inter, KNN); J = inter[nb.ravel()]
    A = A + sp.coo_matrix((np.ones(len(I)), (I, J)), shape=(n, n)).tocsr()
    A = ((A + A.T) > 0).astype(float)
    L = sp.diags(np.asarray(A.sum(1)).ravel()) - A
    free = np.where(~fixed)[0]; fx = np.where(fixed)[0]
    Lff = L[free][:, free]; Lfx = L[free][:, fx]
    x = sla.spsolve(Lff.tocsc(), -Lfx @ val[fx])
    val[free] = np.clip(x, 0, 1)
    r['jaw']['weights'] = {'vertices': inter.tolist(), 'values': val[inter].tolist()}
    return r
if __name__ == '__main__':
    a = [float(x) for x in sys.argv[1:4]]
    print(run(make(*a), show=1)[0])
