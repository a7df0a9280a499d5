function cellValue(row, i, type){var c=row.cells[i];var v=c.getAttribute('data-v');if(v===null)v=c.textContent;
 if(type==='num'){var f=parseFloat(v);return isNaN(f)?Infinity:f;}return v.toLowerCase();}
document.querySelectorAll('table.sortable th').forEach(function(th,i){th.addEventListener('click',function(){
 var table=th.closest('table'),tbody=table.tBodies[0],type=th.getAttribute('data-type');
 var asc=th.getAttribute('data-asc')!=='1';table.querySelectorAll('th').forEach(function(h){h.removeAttribute('data-asc');});
 if(asc)th.setAttribute('data-asc','1');
 var rows=Array.prototype.slice.call(tbody.rows);rows.sort(function(a,b){var x=cellValue(a,i,type),y=cellValue(b,i,type);
  return (x<y?-1:x>y?1:0)*(asc?1:-1);});rows.forEach(function(r){tbody.appendChild(r);});});});
function niceStep(raw){var e=Math.pow(10,Math.floor(Math.log10(raw)));var m=[1,2,5,10];
 for(var k=0;k<m.length;k++){if(m[k]*e>=raw)return m[k]*e;}return 10*e;}
function navViewer(box){
 var d=JSON.parse(box.querySelector('script.nav-view').textContent);
 var cv=box.querySelector('canvas'),ctx=cv.getContext('2d'),sl=box.querySelector('input'),lab=box.querySelector('.t');
 var xs=d.x.concat([d.goal[0]]),ys=d.y.concat([d.goal[1]]);
 d.obs.concat(d.ter||[]).forEach(function(p){p.forEach(function(q){xs.push(q[0]);ys.push(q[1]);});});
 var gimg=null;if(d.gnd){gimg=new Image();gimg.onload=function(){draw(+sl.value);};gimg.src=d.gnd.png;}
 var mov={};(d.mov||[]).forEach(function(m){mov[m.i]=m;var n=m.dx.length-1;
  d.obs[m.i].forEach(function(q){xs.push(q[0]+m.dx[n]);ys.push(q[1]+m.dy[n]);});});
 var x0=Math.min.apply(null,xs)-1,x1=Math.max.apply(null,xs)+1,y0=Math.min.apply(null,ys)-1,y1=Math.max.apply(null,ys)+1;
 // the map inside axes: room on the left and at the bottom for the ticks in metres
 var L=40,B=28,T=6,R=8,W=cv.width-L-R,H=cv.height-B-T;
 var s=Math.min(W/(x1-x0),H/(y1-y0));
 W=(x1-x0)*s;H=(y1-y0)*s;cv.height=Math.ceil(T+H+B);   // the frame hugs the map: no empty band
 function X(x){return L+(x-x0)*s;} function Y(y){return T+H-(y-y0)*s;}
 function poly(p){ctx.beginPath();p.forEach(function(q,i){if(i)ctx.lineTo(X(q[0]),Y(q[1]));else ctx.moveTo(X(q[0]),Y(q[1]));});ctx.closePath();}
 function centre(p){var cx=0,cy=0;p.forEach(function(q){cx+=q[0];cy+=q[1];});return [cx/p.length,cy/p.length];}
 function name(text,x,y,colour){ctx.font='10px sans-serif';var w=ctx.measureText(text).width;
  ctx.fillStyle='rgba(255,255,255,0.75)';ctx.fillRect(X(x)-w/2-2,Y(y)-7,w+4,13);
  ctx.fillStyle=colour;ctx.textAlign='center';ctx.textBaseline='middle';ctx.fillText(text,X(x),Y(y));}
 function axes(){var step=niceStep(Math.max(x1-x0,y1-y0)/6),v;
  var ystep=(y1-y0)/step>=3?step:niceStep((y1-y0)/4);   // a wide, low map keeps >= 3 y ticks
  ctx.strokeStyle='#e0e0e0';ctx.fillStyle='#424242';ctx.font='10px sans-serif';ctx.lineWidth=1;
  ctx.textAlign='center';ctx.textBaseline='top';
  for(v=Math.ceil(x0/step)*step;v<=x1+1e-9;v+=step){ctx.beginPath();ctx.moveTo(X(v),T);ctx.lineTo(X(v),T+H);ctx.stroke();
   ctx.fillText(+v.toFixed(3)+'',X(v),T+H+3);}
  ctx.textAlign='right';ctx.textBaseline='middle';
  for(v=Math.ceil(y0/ystep)*ystep;v<=y1+1e-9;v+=ystep){if(Y(v)<T)continue;ctx.beginPath();ctx.moveTo(L,Y(v));ctx.lineTo(L+W,Y(v));ctx.stroke();
   ctx.fillText(+v.toFixed(3)+'',L-4,Y(v));}
  ctx.strokeStyle='#616161';ctx.strokeRect(L,T,W,H);
  ctx.textAlign='left';ctx.textBaseline='top';ctx.fillText('x, y (m)',2,T+H+14);}
 function scale(){var bar=niceStep((x1-x0)/6),bx=L+W-bar*s-10,by=T+H-10;   // a scale bar, bottom right
  ctx.fillStyle='rgba(255,255,255,0.8)';ctx.fillRect(bx-6,by-17,bar*s+12,22);
  ctx.strokeStyle='#212121';ctx.lineWidth=3;ctx.beginPath();ctx.moveTo(bx,by);ctx.lineTo(bx+bar*s,by);ctx.stroke();ctx.lineWidth=1;
  ctx.fillStyle='#212121';ctx.font='10px sans-serif';ctx.textAlign='center';ctx.textBaseline='bottom';
  ctx.fillText(+bar.toFixed(3)+' m',bx+bar*s/2,by-3);}
 function robot(i){var c=Math.cos(d.yaw[i]),n=Math.sin(d.yaw[i]),l=d.fp.length/2,w=d.fp.width/2;
  if(d.fp.shape==='circle'){ctx.beginPath();ctx.arc(X(d.x[i]),Y(d.y[i]),d.fp.radius*s,0,2*Math.PI);return;}
  poly([[l,w],[-l,w],[-l,-w],[l,-w]].map(function(q){return [d.x[i]+c*q[0]-n*q[1],d.y[i]+n*q[0]+c*q[1]];}));}
 function draw(i){ctx.clearRect(0,0,cv.width,cv.height);axes();
  ctx.save();ctx.beginPath();ctx.rect(L,T,W,H);ctx.clip();
  if(gimg&&gimg.complete){var e=d.gnd.ext;ctx.drawImage(gimg,X(e[0]),Y(e[3]),(e[1]-e[0])*s,(e[3]-e[2])*s);}
  if(d.ter){ctx.strokeStyle='#4e342e';d.ter.forEach(function(p){poly(p);ctx.stroke();});}
  ctx.fillStyle='#9e9e9e';
  d.obs.forEach(function(p,j){var m=mov[j];if(m){ctx.fillStyle='#ffb74d';
    poly(p.map(function(q){return [q[0]+m.dx[i],q[1]+m.dy[i]];}));ctx.fill();ctx.fillStyle='#9e9e9e';}
   else{poly(p);ctx.fill();}});
  ctx.strokeStyle='#2e7d32';ctx.beginPath();ctx.arc(X(d.goal[0]),Y(d.goal[1]),Math.max(3,d.goal[2]*s),0,2*Math.PI);ctx.stroke();
  ctx.lineWidth=2;for(var k=1;k<d.x.length;k++){var f=Math.min(1,d.v[k]/d.vmax);
   ctx.strokeStyle='hsl('+Math.round(260-200*f)+',75%,'+(k<=i?45:80)+'%)';ctx.beginPath();
   ctx.moveTo(X(d.x[k-1]),Y(d.y[k-1]));ctx.lineTo(X(d.x[k]),Y(d.y[k]));ctx.stroke();}
  ctx.strokeStyle='#d50000';robot(i);ctx.stroke();ctx.lineWidth=1;
  if(d.ev&&d.t[i]>=d.ev.t){ctx.fillStyle='#8d1b1b';ctx.beginPath();ctx.moveTo(X(d.ev.x)-7,Y(d.ev.y)-7);
   ctx.lineTo(X(d.ev.x)+7,Y(d.ev.y)-7);ctx.lineTo(X(d.ev.x),Y(d.ev.y)+7);ctx.closePath();ctx.fill();}
  (d.tn||[]).forEach(function(t,j){var c=centre(d.ter[j]);name(t,c[0],c[1]-0.0,'#3e2723');});
  (d.on||[]).forEach(function(t,j){var c=centre(d.obs[j]),m=mov[j];
   name(t,c[0]+(m?m.dx[i]:0),c[1]+(m?m.dy[i]:0),m?'#e65100':'#212121');});
  ctx.restore();scale();
  var up=d.z?', height '+d.z[i].toFixed(2)+' m, pitch '+d.pitch[i].toFixed(1)+' deg nose up'+(d.roll?', roll '+d.roll[i].toFixed(1)+' deg':''):'';
  lab.textContent='t = '+d.t[i].toFixed(2)+' s, speed '+d.v[i].toFixed(2)+' m/s'+up+(d.ev&&d.t[i]>=d.ev.t?', '+d.ev.kind:'')+' (drag to replay)';}
 sl.max=String(d.x.length-1);sl.value=sl.max;sl.addEventListener('input',function(){draw(+sl.value);});draw(d.x.length-1);}
document.querySelectorAll('.viewer').forEach(navViewer);
function sortFailures(key){var box=document.getElementById('failures');
 var items=Array.prototype.slice.call(box.querySelectorAll('section.failure'));
 items.sort(function(a,b){var x=a.dataset[key]+'\u0000'+a.dataset.nodeid,y=b.dataset[key]+'\u0000'+b.dataset.nodeid;
  return x<y?-1:x>y?1:0;});items.forEach(function(s){box.appendChild(s);});}
