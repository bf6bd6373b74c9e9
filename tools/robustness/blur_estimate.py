"""A prototype (not part of gait): the blur of the walker's image, in pixels, by the re-blur
gradient ratio (Zhuo and Sim 2011: at an edge blurred by sigma, re-blurring by s divides the
gradient by sqrt(sigma^2 + s^2) / sigma), the median over the strongest 2 % of edges in a box
round the keypoints of frames 90, 120 and 150 of a run of the sample. Used for the figures of
BENCHMARKS.md, "Blurred and slowed walks"; it reads grey frames written by ffmpeg as there.
The estimate compresses large blurs (sigma 8 reads about 5) but orders them."""
import numpy as np, csv, sys
rows=list(csv.reader(open("/work/main/target/robustness/original/keypoints.csv")))
bp, co = rows[1], rows[2]
def bbox(frame, scale=1.0):
    r=[x for x in rows[3:] if x[0]==str(frame)][0]
    xs=[float(r[i]) for i in range(1,len(r)) if co[i]=="x" and r[i]]
    ys=[float(r[i]) for i in range(1,len(r)) if co[i]=="y" and r[i]]
    x0,x1,y0,y1=min(xs),max(xs),min(ys),max(ys)
    m=0.15*(y1-y0)
    return [int(v*scale) for v in (x0-m,x1+m,y0-m,y1+m)]
def gauss(img, s):
    r=int(3*s+0.5); x=np.arange(-r,r+1); k=np.exp(-x*x/(2*s*s)); k/=k.sum()
    out=np.apply_along_axis(lambda v: np.convolve(v,k,mode='same'),0,img)
    return np.apply_along_axis(lambda v: np.convolve(v,k,mode='same'),1,out)
def grad(img):
    gy,gx=np.gradient(img); return np.hypot(gx,gy)
def sigma(crop, sr=4.0):
    crop=crop.astype(np.float64)
    g=grad(gauss(crop,0.5)); gr=grad(gauss(crop,np.hypot(0.5,sr)))
    # strong edges: top 2% of the reblurred gradient, away from the border
    b=8; g=g[b:-b,b:-b]; gr=gr[b:-b,b:-b]
    t=np.quantile(gr,0.98); m=gr>=t
    R=g[m]/np.maximum(gr[m],1e-6)
    R=R[R>1.0001]
    s=sr/np.sqrt(R*R-1)
    return float(np.median(s))
for name,(w,h) in [("sports2d-demo",(1768,994)),("blur2",(1768,994)),("blur4",(1768,994)),("blur8",(1768,994)),("noise",(1768,994)),("crf28",(1768,994)),("480p",(854,480))]:
    data=np.fromfile(f"/tmp/blur/f_{name}.gray",dtype=np.uint8).reshape(3,h,w)
    out=[]
    for k,f in enumerate([90,120,150]):
        x0,x1,y0,y1=bbox(f, w/1768)
        crop=data[k,max(y0,0):min(y1,h),max(x0,0):min(x1,w)]
        leg=(y1-y0)/1.3*0.5
        out.append(sigma(crop))
    print(name, ["%.2f"%s for s in out], "leg px ~%.0f" % leg)
