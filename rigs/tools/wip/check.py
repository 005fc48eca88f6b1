from proto import *
import subprocess, re, collections
V, F = B.load_obj(DATA/'faces/ict-facekit/generic_neutral_mesh.obj')
PARTS = [(0,'face'),(9409,'head'),(11248,'socket'),(13294,'eyesock'),(14062,'gums'),(17039,'upteeth'),(19247,'loteeth'),(21451,'eyeball'),(24591,'eyesurf'),(25351,'lashes'),(26719,'end')]
def part(v):
    for i in range(len(PARTS)-1):
        if PARTS[i][0] <= v < PARTS[i+1][0]: return PARTS[i][1]
def run(rigjson, opens=(0.25,0.5,0.75,1.0), show=False):
    r = json.load(open(rigjson)) if isinstance(rigjson, str) else rigjson
    w, kind = weights(r, V)
    res = {}
    for o in opens:
        P = pose(r, V, w, o)
        write_obj('/tmp/rig3/p.obj', P, F)
        out = subprocess.run(['/tmp/rig3/selfx_all', '/tmp/rig3/base.obj', '/tmp/rig3/p.obj'], capture_output=True, text=True).stdout
        n = int(re.search(r'new crossings: (\d+)', out).group(1))
        res[o] = n
        if show:
            c = collections.Counter()
            for a, b in re.findall(r'triangles (\d+) and (\d+)', out):
                ta, tb = F[int(a)], F[int(b)]
                c[tuple(sorted((part(ta[0]), part(tb[0]))))] += 1
                if show > 1: print('  ', int(a), int(b), ta, tb, w[ta].round(2), w[tb].round(2))
            print(o, n, dict(c))
    return res, w
if __name__ == '__main__':
    print(run(sys.argv[1], show=int(sys.argv[2]) if len(sys.argv) > 2 else 1)[0])
