"""Where the levelled film is thinnest: its thinnest / mean against the distance from the design's
edge (the test design, tilt 20, planned passes, the plain print (equalise=False) as in docs/rotary.md, the preset's levelling at 0.1 and 1 s).

    PYTHONPATH=src python bench/film_level_edges.py [SIZE_PX]      # default 300
"""
import sys
import numpy as np, tempfile
from pathlib import Path
from scipy import ndimage
from rotoprint import load_device
from rotoprint.rotary import Placement
from rotoprint.rotary.deposit import DepositOptions, LevelOptions, deposit_print
from rotoprint.rotary.testimage import test_design
from rotoprint.rotary.interlace import PassOptions, read_passes
from rotoprint.pipeline.prints import transform_passes
from rotoprint.rotary.options import RotarySetup
from rotoprint.rotary.files import read_print
from rotoprint.rotary.simulate import design_mask
head=load_device("omnidot760").head
n=int(sys.argv[1]) if len(sys.argv) > 1 else 300; d=test_design(n); px=25.4/360
pl=Placement(n,n,px,px,inner_radius_mm=60.0)
with tempfile.TemporaryDirectory() as td:
    transform_passes(d, head, pl, Path(td)/"p.png", PassOptions(RotarySetup(tilt_deg=20.0), passes="auto", equalise=False))
    prs=[read_print(q)[0] for q in read_passes(Path(td)/"p-passes.json")]
for st in (0.1, 1.0):
    dep=deposit_print(prs, d, keep_map=True, options=DepositOptions(level=LevelOptions.from_head(head, set_time_s=st, coats=len(prs))))
    f=dep.films[0]; lv=f.levelled
    L=dep.levelled_thickness; T=dep.thickness
    nx,ny=dep.cells_per_pixel; ox,oy=dep.origin_cells
    m=design_mask(d,1)
    rr=(np.arange(L.shape[0])+0.5-oy)/ny; cc=(np.arange(L.shape[1])+0.5-ox)/nx
    ri=np.clip(np.floor(rr).astype(int),0,n-1); ci=np.clip(np.floor(cc).astype(int),0,n-1)
    okr=(rr>=0)&(rr<n); okc=(cc>=0)&(cc<n)
    dm=m[ri][:,ci]&okr[:,None]&okc[None,:]
    dist=ndimage.distance_transform_edt(dm, sampling=(f.grid_um[1],f.grid_um[0]))
    inter=dm&(dist>=f.footprint_um/2+0.5*min(f.grid_um))
    mean=L[inter].mean()
    print(st, 'landed ttm', f.thinnest_to_mean, 'lev ttm', lv.thinnest_to_mean, 'L um', lv.levelling_length_um)
    for lo,hi in ((0,50),(50,100),(100,200),(200,400),(400,800),(800,1e9)):
        sel=inter&(dist>=lo)&(dist<hi)
        if sel.any(): print('   dist %4d-%4g um: levelled min/mean %.3f landed min/mean %.3f cells %d'%(lo,hi,L[sel].min()/mean,T[sel].min()/T[inter].mean(),sel.sum()))
