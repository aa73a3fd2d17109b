// bt-hls: arithmetic cells onto `$alu`, one per binary operation, before `alumacc`.
//
// alumacc would merge chains of additions into `$macc` cells, which synth_intel's generic
// techmap builds as trees of full-adder LUTs (`$fa`, two cells per bit and operand) around one
// final adder; on the Cyclone IV E carry chain (bt_carry_map.v) a sum of k terms is k - 1
// chained adders of one logic element per bit, as Quartus builds it. So each `$add`, `$sub` and
// `$neg` becomes its own `$alu` here, in the RTL's own order of operations, and comparisons
// become one subtraction read from its sign. Multiplications are left to alumacc.

(* techmap_celltype = "$add $sub" *)
module _80_bt_add_sub (A, B, Y);
	parameter A_SIGNED = 0, B_SIGNED = 0, A_WIDTH = 1, B_WIDTH = 1, Y_WIDTH = 1;
	parameter _TECHMAP_CELLTYPE_ = "";

	(* force_downto *) input [A_WIDTH-1:0] A;
	(* force_downto *) input [B_WIDTH-1:0] B;
	(* force_downto *) output [Y_WIDTH-1:0] Y;

	localparam SUB = _TECHMAP_CELLTYPE_ == "$sub";
	(* force_downto *) wire [Y_WIDTH-1:0] unused_x, unused_co;
	\$alu #(.A_SIGNED(A_SIGNED), .B_SIGNED(B_SIGNED), .A_WIDTH(A_WIDTH), .B_WIDTH(B_WIDTH),
		.Y_WIDTH(Y_WIDTH)) _TECHMAP_REPLACE_ (.A(A), .B(B), .CI(SUB ? 1'b1 : 1'b0),
		.BI(SUB ? 1'b1 : 1'b0), .X(unused_x), .Y(Y), .CO(unused_co));
endmodule

(* techmap_celltype = "$neg" *)
module _80_bt_neg (A, Y);
	parameter A_SIGNED = 0, A_WIDTH = 1, Y_WIDTH = 1;

	(* force_downto *) input [A_WIDTH-1:0] A;
	(* force_downto *) output [Y_WIDTH-1:0] Y;

	// -a = ~a + 1, a extended to the result's width first (so an unsigned operand's
	// inverted upper bits are ones): a constant second operand with BI = 0 keeps it on the
	// chain (bt_carry_map.v leaves constant subtractions, which are comparisons, to LUTs).
	(* force_downto *) wire [Y_WIDTH-1:0] a_ext;
	\$pos #(.A_SIGNED(A_SIGNED), .A_WIDTH(A_WIDTH), .Y_WIDTH(Y_WIDTH)) extend (.A(A), .Y(a_ext));
	(* force_downto *) wire [Y_WIDTH-1:0] not_a = ~a_ext;
	(* force_downto *) wire [Y_WIDTH-1:0] unused_x, unused_co;
	\$alu #(.A_SIGNED(0), .B_SIGNED(0), .A_WIDTH(Y_WIDTH), .B_WIDTH(1),
		.Y_WIDTH(Y_WIDTH)) _TECHMAP_REPLACE_ (.A(not_a), .B(1'b0), .CI(1'b1), .BI(1'b0),
		.X(unused_x), .Y(Y), .CO(unused_co));
endmodule

// Comparisons as one subtraction, read from its sign (the operands extended by one
// bit, so the difference cannot overflow): a < b <=> a - b < 0, a <= b <=> a - b - 1 < 0 (no
// carry-in). alumacc would instead (when it orders the operands the other way round) build
// a > b as ~(a <= b), with an equality reduction over X beside the adder.
(* techmap_celltype = "$lt $le $gt $ge" *)
module _80_bt_cycloneive_cmp (A, B, Y);
	parameter A_SIGNED = 0, B_SIGNED = 0, A_WIDTH = 1, B_WIDTH = 1, Y_WIDTH = 1;
	parameter _TECHMAP_CELLTYPE_ = "", _TECHMAP_CONSTMSK_A_ = 0, _TECHMAP_CONSTMSK_B_ = 0;

	(* force_downto *) input [A_WIDTH-1:0] A;
	(* force_downto *) input [B_WIDTH-1:0] B;
	(* force_downto *) output [Y_WIDTH-1:0] Y;

	localparam SIGNED = A_SIGNED && B_SIGNED;
	localparam W = (A_WIDTH > B_WIDTH ? A_WIDTH : B_WIDTH) + 1;
	localparam WITH_CI = _TECHMAP_CELLTYPE_ == "$lt" || _TECHMAP_CELLTYPE_ == "$ge";
	localparam INVERT = _TECHMAP_CELLTYPE_ == "$ge" || _TECHMAP_CELLTYPE_ == "$gt";

	// A comparison with a constant folds to a few LUTs (to the sign bit against zero).
	wire _TECHMAP_FAIL_ = W <= 3 || _TECHMAP_CONSTMSK_A_ == {A_WIDTH{1'b1}} ||
		_TECHMAP_CONSTMSK_B_ == {B_WIDTH{1'b1}};

	(* force_downto *) wire [W-1:0] diff, unused_x, unused_co;
	\$alu #(.A_SIGNED(SIGNED), .B_SIGNED(SIGNED), .A_WIDTH(A_WIDTH), .B_WIDTH(B_WIDTH),
		.Y_WIDTH(W)) sub (.A(A), .B(B), .CI(WITH_CI ? 1'b1 : 1'b0), .BI(1'b1), .X(unused_x),
		.Y(diff), .CO(unused_co));

	assign Y = {{(Y_WIDTH-1){1'b0}}, INVERT ? ~diff[W-1] : diff[W-1]};
endmodule
