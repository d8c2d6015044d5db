#!/usr/bin/env python3
"""Independent check of specs/wang2013_adaptive_mrac.tsf (plain Python, no numpy).

A second implementation of the adaptive law of docs/adaptive.md and of the truth plant
(J(t) = J + 5 sin t I, disturbance 0.05 sin t rad/s^2, Rodrigues kinematics), with the
spec's parameters written out here: 9 rules on the means of e = omega + 0.5 rho and rho,
A_m = -I, Q = I, rates 0.05 / 1e-8 / 0.1, bounds, layer 1e-3, step 10 ms, RK4 with the
command held. Prints the norms every 5 s and the largest |rho|, |omega| after 40 s, to
compare with `tsfc simulate specs/wang2013_adaptive_mrac.tsf` (its metrics.json).
Usage: python3 specs/tools/check_adaptive.py [lambda] [layer]
"""
import math
import sys
J=[2043.,3044.,1989.]; k1=0.5
def skew(v): return [[0,-v[2],v[1]],[v[2],0,-v[0]],[-v[1],v[0],0]]
def mm(A,B): return [[sum(A[i][k]*B[k][j] for k in range(len(B))) for j in range(len(B[0]))] for i in range(len(A))]
def mv(A,x): return [sum(a*b for a,b in zip(r,x)) for r in A]
def H(r):
    S=skew(r); return [[0.5*((1 if i==j else 0)+S[i][j]+r[i]*r[j]) for j in range(3)] for i in range(3)]
def Amat(w,r):
    Jm=[[J[i] if i==j else 0 for j in range(3)] for i in range(3)]
    Ji=[[1/J[i] if i==j else 0 for j in range(3)] for i in range(3)]
    top=mm(mm(Ji,skew(w)),Jm); top=[[-v for v in row] for row in top]
    Hr=H(r)
    A=[[0]*6 for _ in range(6)]
    for i in range(3):
        for j in range(3):
            A[i][j]=top[i][j]; A[3+i][j]=Hr[i][j]
    return A
pts=[]
for ce,cr in [(0,0),(0,2),(0,-2),(2,0),(2,2),(2,-2),(-2,0),(-2,2),(-2,-2)]:
    w=[ce-0.5*cr]*3; r=[cr]*3
    A=Amat(w,r)
    CA=[[A[k][j]+0.5*A[3+k][j] for j in range(6)] for k in range(3)]
    pts.append((ce,cr,CA))
def tri(z,a,b,c):
    if z<=a or z>=c: return 0.0
    return (z-a)/(b-a) if z<=b else (c-z)/(c-b)
def trap(z,a,b,c,d):
    if z<a or z>d: return 0.0
    if z<b: return (z-a)/(b-a) if b>a else 1.0
    if z<=c: return 1.0
    return (d-z)/(d-c) if d>c else 1.0
def mf(z,c):
    if c==0: return tri(z,-2,0,2)
    if c==2: return trap(z,0,2,100,100)
    return trap(z,-100,-100,-2,0)
lam=float(sys.argv[1]) if len(sys.argv)>1 else 1.0
ga,gb,gd=0.05,1e-8,0.1; phi=float(sys.argv[2]) if len(sys.argv)>2 else 0.001
p=1/(2*lam)
ah=[ [row[:] for row in CA] for _,_,CA in pts]
bh=[[1/J[k] for k in range(3)] for _ in pts]
dh=0.01
x=[0,0,0,1.23,0.55,2.17]; h=0.01; T=60
def f(t,x,u):
    w=x[:3]; r=x[3:]
    Jt=[Jk+5*math.sin(t) for Jk in J]; Jd=5*math.cos(t)
    Jw=[Jt[i]*w[i] for i in range(3)]
    c=[w[1]*Jw[2]-w[2]*Jw[1], w[2]*Jw[0]-w[0]*Jw[2], w[0]*Jw[1]-w[1]*Jw[0]]
    wd=[(u[i]-c[i]-Jd*w[i])/Jt[i]+0.05*math.sin(t) for i in range(3)]
    rd=mv(H(r),w)
    return wd+rd
n=int(round(T/h)); maxrho_after=0; maxw_after=0
for k in range(n+1):
    t=k*h
    s=[x[i]+0.5*x[3+i] for i in range(3)]
    em=sum(s)/3; rm=sum(x[3:])/3
    hw=[mf(em,ce)*mf(rm,cr) for ce,cr,_ in pts]; S=sum(hw); hw=[v/S for v in hw]
    pe=[p*v for v in s]
    u=[0]*3
    for kk in range(3):
        ax=sum(hw[i]*sum(a*b for a,b in zip(ah[i][kk],x)) for i in range(9))
        bb=sum(hw[i]*bh[i][kk] for i in range(9))
        sat=max(-1,min(1,pe[kk]/phi))
        u[kk]=(-lam*s[kk]-ax-dh*sat)/bb
    for i in range(9):
        for kk in range(3):
            for j in range(6):
                ah[i][kk][j]=min(10,max(-10,ah[i][kk][j]+h*ga*hw[i]*x[j]*pe[kk]))
            bh[i][kk]=min(1e-3,max(2e-4,bh[i][kk]+h*gb*hw[i]*u[kk]*pe[kk]))
    dh=min(0.2,max(0,dh+h*gd*sum(abs(v) for v in pe)))
    if t>=40:
        maxrho_after=max(maxrho_after,math.sqrt(sum(v*v for v in x[3:])))
        maxw_after=max(maxw_after,math.sqrt(sum(v*v for v in x[:3])))
    if k%500==0: print(f"t={t:5.1f} |w|={math.sqrt(sum(v*v for v in x[:3])):.3e} |rho|={math.sqrt(sum(v*v for v in x[3:])):.3e} |s|={math.sqrt(sum(v*v for v in s)):.3e} dh={dh:.4f} u={[round(v,1) for v in u]}")
    if k==n: break
    k1_=f(t,x,u); x2=[a+0.5*h*b for a,b in zip(x,k1_)]
    k2_=f(t+h/2,x2,u); x3=[a+0.5*h*b for a,b in zip(x,k2_)]
    k3_=f(t+h/2,x3,u); x4=[a+h*b for a,b in zip(x,k3_)]
    k4_=f(t+h,x4,u)
    x=[a+h/6*(b+2*c+2*d+e) for a,b,c,d,e in zip(x,k1_,k2_,k3_,k4_)]
print("max |rho| after 40:",maxrho_after," max |w| after 40:",maxw_after)
