// bt-hls: techmap of `$mul` up to 18 x 18 bits onto one Cyclone IV E embedded multiplier
// (cycloneive_mac_mult, unregistered, + cycloneive_mac_out in bypass), as Quartus maps an
// lpm_mult of these widths; wider products fail the map and stay in logic. The generated PEs
// write their wide products as 18 x 18 partial products (see bt-hls's rtl::pe), so every
// `$mul` of a design fits one block. Runs before alumacc, which would turn `$mul` into `$macc`.
(* techmap_celltype = "$mul" *)
module _bt_mul_to_mac (A, B, Y);
  parameter A_SIGNED = 0;
  parameter B_SIGNED = 0;
  parameter A_WIDTH = 1;
  parameter B_WIDTH = 1;
  parameter Y_WIDTH = 1;
  input [A_WIDTH-1:0] A;
  input [B_WIDTH-1:0] B;
  output [Y_WIDTH-1:0] Y;
  localparam P_WIDTH = A_WIDTH + B_WIDTH;
  wire _TECHMAP_FAIL_ = A_WIDTH > 18 || B_WIDTH > 18 || A_SIGNED != B_SIGNED;
  wire [P_WIDTH-1:0] p, q;
  cycloneive_mac_mult #(
    .dataa_width(A_WIDTH),
    .datab_width(B_WIDTH),
    .dataa_clock("none"),
    .datab_clock("none"),
    .signa_clock("none"),
    .signb_clock("none"),
    .lpm_type("cycloneive_mac_mult")
  ) mult (
    .dataa(A),
    .datab(B),
    .signa(A_SIGNED ? 1'b1 : 1'b0),
    .signb(B_SIGNED ? 1'b1 : 1'b0),
    .clk(1'b0),
    .aclr(1'b0),
    .ena(1'b1),
    .dataout(p)
  );
  cycloneive_mac_out #(
    .dataa_width(P_WIDTH),
    .output_clock("none"),
    .lpm_type("cycloneive_mac_out")
  ) out (
    .dataa(p),
    .clk(1'b0),
    .aclr(1'b0),
    .ena(1'b1),
    .dataout(q)
  );
  generate
    if (Y_WIDTH <= P_WIDTH)
      assign Y = q[Y_WIDTH-1:0];
    else if (A_SIGNED)
      assign Y = {{(Y_WIDTH - P_WIDTH){q[P_WIDTH-1]}}, q};
    else
      assign Y = {{(Y_WIDTH - P_WIDTH){1'b0}}, q};
  endgenerate
endmodule
