"""Square to the block grid (0°), can a coarse JPEG's Y′ give back more than
sweepmtf's moment fit reads? A prototype (session 20), not part of the tool.

A log sweep 0.02–0.45 cy/px across 1024 × 128 px, every row the same local
sine in linear light (modulation 0.8 × a Gaussian lens × pixel aperture),
sRGB-encoded, Gaussian noise in code values, stored by Pillow's libjpeg as a
grey JPEG at the given quality, decoded. For windows of 4 cycles (at least
24 px) it compares two estimates with the true modulation:

- moment: the rows' mean profile, linearised, least-squares a + b·sin φ +
  c·cos φ + d·x (φ the exact phase), modulation √(b² + c²)/a;
- ML: the file's own quantised DCT coefficients (recovered exactly from the
  decoded 8×8 blocks and the file's table) as interval-censored data, the
  model's block coefficients DCT(enc(μ(1 + t·x)(1 + m sin φ))) with Gaussian
  noise, likelihood maximised over (m, μ, t).

Run: python3 jpeg_square_ml.py SEED [LENS_SIGMA_PX [MEAN_LINEAR [NOISE_CODES [QUALITY]]]]
(needs numpy, scipy, pillow).
"""
import numpy as np, io, sys
from PIL import Image
from scipy.optimize import minimize
from scipy.special import ndtr, log_ndtr
from scipy.fft import dctn
a=sys.argv
seed=int(a[1]) if len(a)>1 else 1
sig=float(a[2]) if len(a)>2 else 0.55
mu=float(a[3]) if len(a)>3 else 0.35
noise=float(a[4]) if len(a)>4 else 0.8
Q=int(a[5]) if len(a)>5 else 75
rng=np.random.default_rng(seed)
W,H=1024,128
f0,f1=0.02,0.45
x=np.arange(W)+0.5
kk=np.log(f1/f0)/W
ph0=rng.uniform(0,2*np.pi)
def phase(x): return 2*np.pi*f0*(np.exp(kk*x)-1)/kk+ph0
def freq(x): return f0*np.exp(kk*x)
m0=0.8
def mtf(f): return np.exp(-2*np.pi**2*sig**2*f**2)*np.sinc(f)
def enc(L):
    L=np.clip(L,0,1); return np.where(L<=0.0031308,12.92*L,1.055*np.maximum(L,1e-12)**(1/2.4)-0.055)
def dec(v):
    return np.where(v<=0.04045,v/12.92,((v+0.055)/1.055)**2.4)
Lrow=mu*(1+m0*mtf(freq(x))*np.sin(phase(x)))
img=np.clip(np.round(255*enc(Lrow)[None,:]+rng.normal(0,noise,(H,W))),0,255).astype(np.uint8)
buf=io.BytesIO(); Image.fromarray(img,'L').save(buf,'JPEG',quality=Q); buf.seek(0)
im=Image.open(buf); qraw=np.array(im.quantization[0])
d=np.array(im).astype(float)
blocks=(d-128).reshape(H//8,8,W//8,8).transpose(0,2,1,3)   # by,bx,8,8
F=dctn(blocks,axes=(-2,-1),norm='ortho')
zz=np.array([0,1,8,16,9,2,3,10,17,24,32,25,18,11,4,5,12,19,26,33,40,48,41,34,27,20,13,6,7,14,21,28,35,42,49,56,57,50,43,36,29,22,15,23,30,37,44,51,58,59,52,45,38,31,39,46,53,60,61,54,47,55,62,63])
best=None
for name,q in [('natural',qraw.reshape(8,8)), ('zigzag',np.zeros(64))]:
    if name=='zigzag':
        q=np.zeros(64); q[zz]=qraw; q=q.reshape(8,8)
    r=F/q; res=np.abs(r-np.round(r)).max()
    if best is None or res<best[0]: best=(res,name,q)
res,qname,q=best
K=np.round(F/q)
print('table',qname,'max recovery residual %.3f'%res, 'q row0',q[0])
# estimators per window: centre x_c, 4 cycles wide
sn=np.hypot(noise,np.sqrt(1/12))
def fit_moment(xs,prof):
    ph=phase(xs); A=np.stack([np.ones_like(xs),np.sin(ph),np.cos(ph),xs-xs.mean()],1)
    c=np.linalg.lstsq(A,prof,rcond=None)[0]; return np.hypot(c[1],c[2])/c[0], c
def nll(p,bx,xsb):
    m,muv,tilt=p
    # predicted linear block rows (same for all rows)
    L=muv*(1+tilt*(xsb-xsb.mean()))*(1+m*np.sin(phase(xsb)))   # (nb,8)
    P=255*enc(L)-128
    blk=np.repeat(P[:,None,:],8,axis=1)       # nb,8,8 (rows identical)
    C=dctn(blk,axes=(-2,-1),norm='ortho')    # nb,8,8
    lo=(K[:,bx]-0.5)*q; hi=(K[:,bx]+0.5)*q     # by,nb,8,8
    Cb=C[None]
    # P(lo<C+n<hi)
    pr=ndtr((hi-Cb)/sn)-ndtr((lo-Cb)/sn)
    return -np.sum(np.log(np.maximum(pr,1e-300)))
prof=dec(d/255).mean(0)
out=[]
for xc in np.arange(40,W-16,12.0):
    f=freq(xc); half=max(2/f,12.0)
    sel=(x>xc-half)&(x<xc+half)
    if sel.sum()<16: continue
    mm,c=fit_moment(x[sel],prof[sel])
    # truth modulation at xc
    mt=m0*mtf(f)
    # blocks whose centre within window
    bxs=np.arange(W//8); bc=bxs*8+4
    bsel=bxs[(bc>xc-half)&(bc<xc+half)]
    if len(bsel)<2: continue
    xsb=(bsel[:,None]*8+np.arange(8)[None,:]+0.5).astype(float)
    r=minimize(nll,[mm,c[0],c[3]/c[0]],args=(bsel,xsb),method='Nelder-Mead',options={'xatol':1e-6,'fatol':1e-6,'maxiter':2000})
    out.append((f,mt,mm,r.x[0]))
out=np.array(out)
print(' f     truth   moment%%  ML%%')
for f,mt,mm,ml in out[out[:,0]>0.2]:
    print('%.3f %.4f %+6.2f %+6.2f'%(f,mt,100*(mm/mt-1),100*(ml/mt-1)))
sel=(out[:,0]>0.05)&(out[:,0]<0.4)
hi=out[:,0]>0.3
print('largest |error| above 0.3 cy/px: moment %.2f%%  ML %.2f%%'%(100*np.max(abs(out[hi,2]/out[hi,1]-1)),100*np.max(abs(out[hi,3]/out[hi,1]-1))))
print('RMS rel err 0.05-0.4: moment %.2f%%  ML %.2f%%'%(100*np.sqrt(np.mean((out[sel,2]/out[sel,1]-1)**2)),100*np.sqrt(np.mean((out[sel,3]/out[sel,1]-1)**2))))
print('mean rel err: moment %+.2f%%  ML %+.2f%%'%(100*np.mean(out[sel,2]/out[sel,1]-1),100*np.mean(out[sel,3]/out[sel,1]-1)))
